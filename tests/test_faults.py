"""Bad input and faults, as a new user meets them: every case is a one-line error or a correct run.

Property-based (hypothesis) for params files and terrain files; one fault test per stage (collect, train-vae,
train-ppo, evaluate) through the CLI. "One line" means: exit code 2, one non-empty line of output, no traceback.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from orphans import kill_and_list_survivors
from pydantic import BaseModel
from typer.testing import CliRunner

from hexpipe.cli import app
from hexpipe.collect import collect
from hexpipe.config import ConfigError, Params, load_params
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.recording.manifest import MANIFEST
from hexpipe.recording.reader import iter_frames
from hexpipe.sim.terrain import TerrainError, load_terrain, realize

ROOT = Path(__file__).resolve().parents[1]
runner = CliRunner()
SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)


def one_line_error(result: Any) -> str:
    """Assert the CLI failed with one line (no traceback) and return it."""
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert result.exit_code == 2, result.output
    assert len(lines) == 1 and "Traceback" not in result.output, result.output
    assert not isinstance(result.exception, Exception) or isinstance(result.exception, SystemExit), result.exception
    return lines[0]


# ------------------------------------------------------------------------------------------ params (hypothesis)

FIELDS = [
    (section, key)
    for section, field in Params.model_fields.items()
    for key, sub in field.annotation.model_fields.items()
    if not (isinstance(sub.annotation, type) and issubclass(sub.annotation, BaseModel))
]
SPECIAL = st.sampled_from([math.inf, -math.inf, math.nan, 1e300, -0.0, 0, -1, True, False, None, "", "1e-3"])
SCALAR = st.one_of(st.integers(-5, 100_000), st.floats(-1e4, 1e4), st.booleans(), st.text(max_size=4), SPECIAL)
WILD = st.one_of(SCALAR, st.lists(SCALAR, max_size=4), st.dictionaries(st.text(max_size=3), SCALAR, max_size=2))


def near(default: Any) -> st.SearchStrategy[Any]:
    """Values of the default's own type and scale: mostly valid, so that valid configs get run too."""
    if isinstance(default, bool):
        return st.booleans()
    if isinstance(default, int):  # a negative default is a sentinel (ppo.sde_sample_freq=-1): around it, up to 1
        return st.integers(min(default, max(0, default // 4)), max(default * 2 + 1, 1))
    if isinstance(default, float):
        return st.floats(*sorted((0.5 * default, 1.5 * default))) if default else st.floats(0, 0.2)
    if isinstance(default, tuple | list) and default and not isinstance(default[0], str):
        return st.tuples(*(near(v) for v in default)).map(list)
    return st.just(list(default) if isinstance(default, tuple) else default)


def change(field: tuple[str, str]) -> st.SearchStrategy[tuple[tuple[str, str], Any]]:
    default = getattr(getattr(Params(), field[0]), field[1])
    return st.tuples(st.just(field), st.one_of(near(default), near(default), WILD))


CHANGE = st.sampled_from(FIELDS).flatmap(change)


def step_env(params: Params, terrain: str = "single_block", steps: int = 3) -> None:
    """A valid config must also work: build the env and take a few steps."""
    env = HexapodEnv(terrain, sim=params.sim, cpg=params.cpg, sensors=params.sensors, task=params.task)
    try:
        env.reset(seed=0)
        for _ in range(steps):
            _, reward, *_ = env.step(np.zeros(3, dtype=np.float32))
        assert math.isfinite(reward)
    finally:
        env.close()


@SETTINGS
@given(changes=st.lists(CHANGE, min_size=1, max_size=3))
def test_any_params_file_gives_one_line_or_a_working_config(tmp_path_factory, changes):
    tmp = tmp_path_factory.mktemp("params")
    tree = yaml.safe_load((ROOT / "params.yaml").read_text())
    for (section, key), value in changes:
        tree[section][key] = value
    path = tmp / "params.yaml"
    path.write_text(yaml.safe_dump(tree, allow_unicode=True))
    overrides = [f"vae.data_dir={tmp / 'none'}", f"vae.out_dir={tmp / 'vae'}", f"vae.report_dir={tmp / 'r'}"]
    result = runner.invoke(app, ["train-vae", "--params", str(path), *(a for o in overrides for a in ("--set", o))])
    line = one_line_error(result)
    if "no such folder" in line:  # the params were valid: they must work, too
        event("valid params")
        step_env(load_params(path, overrides))
    else:
        event("one-line error")
        assert str(path) in line


def test_params_file_faults_are_one_line(tmp_path):
    cases = {
        "": "the file is empty",
        "# nothing but a comment\n": "the file is empty",
        "sim:\n  friction: 1.0\n  friction: 2.0\n": "line 3: duplicate key 'friction'",
        "collect:\n  episodes: true\n": "collect.episodes: expected a number or text, not a boolean",
        "sensors:\n  heightmap_ahead: [.nan, 1.4]\n": "sensors.heightmap_ahead[0]: Input should be a finite number",
        "sim:\n  friction: .inf\n": "sim.friction: Input should be a finite number",
        "vae:\n  image_size: 40\n": "vae.image_size: must be a multiple of 16",
        "task:\n  terrain: flat\n": "unknown key 'task.terrain'",
        "sensors:\n  heightmap_rows: 100000\n": "sensors.heightmap_rows",
    }
    for text, expected in cases.items():
        path = tmp_path / "p.yaml"
        path.write_text(text)
        line = one_line_error(runner.invoke(app, ["bench", "--params", str(path)]))
        assert expected in line and str(path) in line, (text, line)
    path = tmp_path / "p.yaml"
    path.write_bytes(b"sim:\n  friction: \xff\xfe\n")  # not text: unreadable as YAML
    assert "cannot read (UnicodeDecodeError)" in one_line_error(runner.invoke(app, ["bench", "--params", str(path)]))
    with pytest.raises(ConfigError, match="duplicate key 'a'"):
        load_params(ROOT / "params.yaml", ["sim={a: 1, a: 2}"])
    (tmp_path / "p.yaml").write_text("{}\n")  # all defaults, said on purpose
    assert load_params(tmp_path / "p.yaml") == Params()


# ----------------------------------------------------------------------------------------- terrain (hypothesis)

WILD_NUM = st.sampled_from([0, -1, 1e9, -1e9, math.inf, math.nan, "x", True, None, [1, 2]])
POS = st.one_of(*[st.floats(0.02, 1.5)] * 9, WILD_NUM)  # mostly valid: valid terrains must be walked on too
NUM = st.one_of(*[st.floats(-1, 3)] * 9, WILD_NUM)


def pair(values: st.SearchStrategy[Any]) -> st.SearchStrategy[Any]:
    ordered = st.lists(values, min_size=2, max_size=2).map(lambda v: sorted(v, key=str))
    return st.one_of(*[ordered] * 9, WILD_NUM)


COUNT = st.one_of(st.lists(st.integers(0, 6), min_size=2, max_size=2).map(sorted),
                  st.lists(st.integers(0, 300), min_size=2, max_size=2).map(sorted),
                  st.sampled_from([[100_000, 100_000], [3, 1], [1.5, 2]]))
BOX = st.one_of(
    st.fixed_dictionaries({"center": st.lists(NUM, min_size=3, max_size=3), "size": st.lists(POS, min_size=3,
                                                                                              max_size=3)}),
    st.fixed_dictionaries({"face": NUM, "depth": POS, "height": POS}, optional={"width": POS, "y": NUM}),
    st.fixed_dictionaries({"face": NUM, "bogus": NUM}),
)
TERRAIN = st.one_of(
    st.fixed_dictionaries({}, optional={
        "friction": POS,
        "boxes": st.lists(BOX, max_size=4),
        "rough": st.fixed_dictionaries({}, optional={
            "x": st.sampled_from([[0.4, 3.0], [1.0, 2.0], [0.0, 99.0], [2.0, 1.0]]), "y": pair(NUM),
            "cell": st.sampled_from([0.05, 0.1, 0.001, 1e-6, 0.5]), "amplitude": POS,
            "smoothing": st.sampled_from([0.1, 0.3, 5.0, 1000.0, 0.0]), "ramp": POS, "flat": POS}),
        "stairs": st.fixed_dictionaries({}, optional={"start": NUM, "steps": st.integers(-1, 300), "rise": POS,
                                                      "run": POS, "top": POS}),
        "random_blocks": st.fixed_dictionaries({}, optional={"count": COUNT, "height": pair(POS),
                                                             "depth": pair(POS), "face": pair(NUM), "gap": POS}),
    }),
    st.sampled_from([None, [], "boxes", {"nonsense": 1}, {"boxes": "many"}, {"rough": [1, 2]}]),
)


@SETTINGS
@given(data=TERRAIN)
def test_any_terrain_file_gives_one_line_or_a_walkable_terrain(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("terrain") / "course.yaml"
    path.write_text(yaml.safe_dump(data))
    try:
        recipe = load_terrain(str(path))
    except TerrainError as exc:
        event("one-line error")
        assert "\n" not in str(exc) and str(exc).startswith(str(path)), exc
        return
    event("valid terrain")
    terrain = realize(recipe, np.random.default_rng(0))
    assert np.isfinite(terrain.height_at(np.linspace(0, 3, 50), np.zeros(50))).all()
    step_env(Params(), terrain=str(path), steps=2)


def test_terrain_file_faults_are_one_line(tmp_path):
    cases = {
        "boxes:\n  - {face: 1, depth: 0.3, height: 0.1}\nboxes: []\n": "line 3: duplicate key 'boxes'",
        "random_blocks: {count: [100000, 100000]}\n": "random_blocks.count",
        "rough: {smoothing: 1000}\n": "smoothing 1000.0 m",
        "rough: {x: [0, 99], y: [-50, 50]}\n": "at most 250000",
        "boxes: [" + ", ".join(["{face: 1, depth: 0.1, height: 0.1}"] * 201) + "]\n": "at most 200",
    }
    (tmp_path / "t.yaml").write_bytes(b"boxes: \xff\n")
    with pytest.raises(TerrainError, match="cannot read"):
        load_terrain(str(tmp_path / "t.yaml"))
    for text, expected in cases.items():
        path = tmp_path / "t.yaml"
        path.write_text(text)
        with pytest.raises(TerrainError) as err:
            load_terrain(str(path))
        assert expected in str(err.value) and "\n" not in str(err.value), (text, err.value)


# ------------------------------------------------------------------------------------------- stage faults


def tiny_collect(out: Path, episodes: int = 3) -> Params:
    return load_params(ROOT / "params.yaml", [f"collect.episodes={episodes}", "collect.max_seconds=0.5",
                                              "collect.workers=2", f"collect.out_dir={out}"])


def test_collect_repairs_damaged_episodes_and_refuses_a_malformed_manifest(tmp_path):
    out = tmp_path / "rollouts"
    params = tiny_collect(out)
    collect(params, say=lambda _: None)
    rows = json.loads((out / MANIFEST).read_text())["episodes"]
    first, second = out / rows[0]["file"], out / rows[1]["file"]
    first.write_bytes(first.read_bytes()[:-100])  # truncated in place
    data = bytearray(second.read_bytes())
    data[len(data) // 2] ^= 0xFF  # one flipped byte, same size
    second.write_bytes(bytes(data))
    (out / "ep_99999_foreign.mcap").write_bytes(b"not ours")
    notes: list[str] = []
    report = collect(params, say=notes.append)
    assert report["episodes_run_now"] == 2 and report["episodes"] == 3
    assert any(rows[0]["file"] in n and "damaged" in n and "the manifest says" in n for n in notes), notes
    assert any(rows[1]["file"] in n and "changed since it was written" in n for n in notes), notes
    assert not (out / "ep_99999_foreign.mcap").exists()
    for row in json.loads((out / MANIFEST).read_text())["episodes"]:
        assert sum(1 for _ in iter_frames(out / row["file"])) == row["frames"]

    report_path = tmp_path / "collect.json"
    manifest = out / MANIFEST
    good = manifest.read_text()
    for bad, expected in [("{not json", "not a JSON manifest"), ("[1, 2]", "no 'signature'"),
                          (json.dumps({**json.loads(good), "episodes": [{"file": 3}]}), "episodes[0]")]:
        manifest.write_text(bad)
        result = runner.invoke(app, ["collect", "--set", f"collect.out_dir={out}", "--set", "collect.episodes=3",
                                     "--set", "collect.max_seconds=0.5", "--report", str(report_path)])
        line = one_line_error(result)
        assert str(manifest) in line and expected in line, line
        assert len(list(out.glob("*.mcap"))) == 3  # nothing deleted on the strength of a manifest it cannot read


def test_unwritable_output_folders_fail_before_any_work(tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    cases = [
        ["collect", "--set", f"collect.out_dir={blocker}/rollouts"],
        ["train-vae", "--set", f"vae.out_dir={blocker}/vae", "--set", f"vae.data_dir={tmp_path}/none"],
        ["train-ppo", "--set", f"ppo.report_dir={blocker}/ppo", "--set", f"ppo.encoder_dir={tmp_path}/none"],
        ["evaluate", "--set", f"eval.out_dir={blocker}/eval"],
    ]
    for args in cases:
        line = one_line_error(runner.invoke(app, [*args]))
        assert f"{blocker}/" in line and "cannot write outputs here" in line, line


def test_an_unknown_training_terrain_is_one_line_before_any_worker_starts(tmp_path):
    args = ["train-ppo", "--set", "ppo.blind=true", "--set", "ppo.train_terrains=[varied_opn]",
            "--set", f"ppo.out_dir={tmp_path}/ppo", "--set", f"ppo.report_dir={tmp_path}/reports"]
    line = one_line_error(runner.invoke(app, args))
    assert "unknown terrain 'varied_opn'" in line and "varied_open" in line, line


def test_train_vae_reads_only_the_manifest_episodes(tmp_path):
    out = tmp_path / "rollouts"
    collect(tiny_collect(out, episodes=2), say=lambda _: None)
    listed = {row["file"] for row in json.loads((out / MANIFEST).read_text())["episodes"]}
    stray = out / "zz_copied_in.mcap"
    shutil.copy(out / sorted(listed)[0], stray)
    assert {f.episode for f in iter_frames(out)} == {Path(f).stem for f in listed}  # the copy is not read
    from rich.console import Console

    from hexpipe.models.vae_data import note_unlisted

    console = Console(record=True, width=200)
    note_unlisted(out, console)
    text = console.export_text()
    assert "ignoring 1 .mcap file(s)" in text and stray.name in text

    (out / MANIFEST).write_text(json.dumps({"signature": "x", "episodes": "all"}))
    line = one_line_error(runner.invoke(app, ["train-vae", "--set", f"vae.data_dir={out}",
                                              "--set", f"vae.out_dir={tmp_path / 'vae'}",
                                              "--set", f"vae.report_dir={tmp_path / 'r'}"]))
    assert "episodes" in line and MANIFEST in line


def test_train_ppo_resume_of_a_finished_run_says_so(tmp_path):
    args = ["train-ppo", "--resume", "--set", "ppo.candidates=1", "--set", "ppo.validation_episodes=2",
            "--set", "ppo.blind=true", "--set", "ppo.n_envs=1", "--set", "ppo.n_steps=64",
            "--set", "ppo.batch_size=64", "--set", "ppo.n_epochs=1", "--set", "ppo.total_timesteps=64",
            "--set", "ppo.train_terrains=[single_block]", "--set", "task.time_limit=2.0",
            "--set", f"ppo.out_dir={tmp_path / 'ppo'}", "--set", f"ppo.report_dir={tmp_path / 'r'}"]
    first = runner.invoke(app, args)
    assert first.exit_code == 0 and "train-ppo: 64 steps" in first.output, first.output
    again = runner.invoke(app, args)
    assert again.exit_code == 0 and "nothing to do" in again.output, again.output
    shorter = runner.invoke(app, [*args, "--set", "ppo.total_timesteps=32", "--set", "ppo.n_steps=32",
                                  "--set", "ppo.batch_size=32"])
    assert shorter.exit_code == 0 and "train-ppo: 32 steps" in shorter.output, shorter.output


def test_evaluate_never_names_or_deletes_outside_its_folder(tmp_path):
    from hexpipe.evaluation.run import _remove_stale
    from hexpipe.evaluation.suite import Scenario, evaluation_suite

    terrain = tmp_path / "terrains" / "...yaml"  # stem ".."
    terrain.parent.mkdir()
    terrain.write_text("boxes: [{face: 1.0, depth: 0.3, height: 0.1}]\n")
    params = load_params(ROOT / "params.yaml", [f"eval.out_dir={tmp_path / 'eval' / 'out'}"])
    suite = evaluation_suite(params, [str(terrain)])
    assert all(s.stem not in ("", ".", "..") and "/" not in s.stem and not s.stem.startswith(".") for s in suite)
    outside = tmp_path / "eval" / "ep_0.mcap"
    outside.parent.mkdir()
    outside.write_bytes(b"someone else's")
    _remove_stale(Path(params.eval.out_dir), [Scenario(str(terrain), "..", suite[-1].recipe)], written=set())
    assert outside.exists()
    # through the CLI: a missing policy is a one-line error, and the file outside is still there
    line = one_line_error(runner.invoke(app, [
        "evaluate", "--no-summary", "--terrain", str(terrain), "--set", f"eval.out_dir={tmp_path / 'eval' / 'out'}",
        "--set", f"eval.report_dir={tmp_path / 'r'}", "--set", f"eval.policy_dir={tmp_path / 'no-policy'}"]))
    assert "no-policy" in line and outside.exists()


def test_env_workers_die_with_a_killed_train_ppo(tmp_path):
    """kill -9 of train-ppo alone: its SubprocVecEnv workers must not live on."""
    import subprocess
    import sys

    proc = subprocess.Popen(
        [sys.executable, "-m", "hexpipe.cli", "train-ppo", "--set", "ppo.blind=true", "--set", "ppo.n_envs=2",
         "--set", f"ppo.out_dir={tmp_path / 'ppo'}", "--set", f"ppo.report_dir={tmp_path / 'r'}"],
        cwd=ROOT, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    alive = kill_and_list_survivors(proc)
    assert not alive, f"env workers {alive} outlived train-ppo"
