"""`hexpipe sweep` on real Ray clusters, bound to 127.0.0.1: a tiny local sweep with a trial that fails on purpose,
resume after kill -9 of the driver, and a two-node cluster on this machine.

Every test keeps Ray's state to itself: RAY_TMPDIR (a short path: Ray's socket names must fit 107 bytes) and HOME
(where Ray keeps ~/.ray/auth_token) point into fresh temp folders, and RAY_ADDRESS is unset.
"""

import contextlib
import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from hexpipe.config import ConfigError, apply_overrides, load_params
from hexpipe.models.vae import ConvVAE, encoder_config, export_encoder
from hexpipe.sweep.grid import expand, parse_condition
from hexpipe.sweep.run import run_sweep
from hexpipe.sweep.runner import eta_seconds, format_seconds

ROOT = Path(__file__).resolve().parents[1]
HEXPIPE = [sys.executable, "-m", "hexpipe.cli"]
TINY = ["ppo.total_timesteps=64", "ppo.n_steps=64", "ppo.batch_size=64", "ppo.n_epochs=1", "ppo.n_envs=1",
        "ppo.train_terrains=[single_block]", "task.time_limit=2.0", "eval.terrains=[single_block]",
        "eval.episodes=1", "eval.grid_a=[0.3]", "eval.grid_b=[0.3]", "eval.grid_omega=[4.712389]", "eval.workers=1",
        "sweep.resamples=200", "ppo.candidates=1", "ppo.validation_episodes=2"]


@pytest.fixture
def ray_env(tmp_path, monkeypatch):
    """Ray's temp folder, token and address private to this test (for this process and its children)."""
    ray_tmp = tempfile.mkdtemp(prefix="ray", dir="/tmp")
    monkeypatch.setenv("RAY_TMPDIR", ray_tmp)
    monkeypatch.setenv("MPLCONFIGDIR", os.environ.get("MPLCONFIGDIR", str(Path.home() / ".config/matplotlib")))
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    for name in ("RAY_ADDRESS", "RAY_AUTH_MODE", "RAY_AUTH_TOKEN", "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"):
        monkeypatch.setenv(name, "")  # recorded, so that teardown also drops what Ray or the sweep set in-process
        monkeypatch.delenv(name)
    (tmp_path / "home").mkdir()
    yield dict(os.environ)
    shutil.rmtree(ray_tmp, ignore_errors=True)


def sets(tmp_path: Path, *extra: str) -> list[str]:
    return [*TINY, f"sweep.data_dir={tmp_path / 'data'}", f"sweep.report_dir={tmp_path / 'reports'}", *extra]


def cli_args(tmp_path: Path, *extra: str) -> list[str]:
    return [a for s in sets(tmp_path) for a in ("--set", s)] + list(extra)


def test_grid_expands_conditions_by_seeds_and_refuses_owned_keys(tmp_path):
    params = load_params(ROOT / "params.yaml", sets(tmp_path, "sweep.name=g", "sweep.seeds=[3, 4]",
                                                    "sweep.conditions={a: [], b: [ppo.blind=true]}"))
    trials = expand(params)
    assert [t.name for t in trials] == ["a-seed3", "b-seed3", "a-seed4", "b-seed4"]  # seed-major
    assert [t.params.ppo.seed for t in trials] == [3, 3, 4, 4] and trials[1].params.ppo.blind
    assert trials[2].params.ppo.out_dir == str(tmp_path / "data" / "g" / "a-seed4" / "ppo")
    assert trials[2].params.eval.report_dir == str(tmp_path / "reports" / "g" / "a-seed4" / "eval")
    assert not trials[0].params.eval.record_video and trials[0].params.eval.log_episodes == 0
    assert len({t.key for t in trials}) == 4 and trials[0].cpus == 1
    same = expand(load_params(ROOT / "params.yaml", [*sets(tmp_path, "sweep.name=g", "sweep.seeds=[3, 4]",
                                                          "sweep.conditions={a: [], b: [ppo.blind=true]}"),
                                                     "sweep.resamples=500", "sweep.cpus=7"]))
    assert [t.key for t in same] == [t.key for t in trials]  # statistics settings do not invalidate trials
    upstream = expand(apply_overrides(params, ["vae.epochs=3", "collect.episodes=5"]))
    assert [t.key for t in upstream] == [t.key for t in trials]  # nor do the stages before train-ppo
    longer = expand(apply_overrides(params, ["ppo.n_steps=256"]))
    assert not {t.key for t in longer} & {t.key for t in trials}
    assert parse_condition("x:ppo.blind=true; task.power_cost=0.1") == ("x", ("ppo.blind=true",
                                                                               "task.power_cost=0.1"))
    assert parse_condition("default") == ("default", ())
    bad = load_params(ROOT / "params.yaml", ["sweep.conditions={a: [ppo.out_dir=elsewhere]}"])
    with pytest.raises(ConfigError, match=r"ppo\.out_dir is set by the sweep"):
        expand(bad)
    with pytest.raises(ConfigError, match=r"sweep\.seeds: .*duplicate seeds"):
        load_params(ROOT / "params.yaml", ["sweep.seeds=[1, 1]"])
    with pytest.raises(ConfigError, match=r"eval\.workers"):
        load_params(ROOT / "params.yaml", ["eval.workers=0"])


def test_trials_that_train_their_encoder_draw_it_with_their_seed(tmp_path):
    conditions = {"a": [], "b": ["ppo.blind=true"], "c": ["vae.feature_weight=2"]}
    args = ("sweep.name=g", "sweep.seeds=[3, 4]", f"sweep.conditions={json.dumps(conditions)}")
    trials = {t.name: t for t in expand(load_params(ROOT / "params.yaml",
                                                    sets(tmp_path, *args, "sweep.train_encoder=true")))}
    a3, b3, c3, a4 = trials["a-seed3"], trials["b-seed3"], trials["c-seed3"], trials["a-seed4"]
    assert a3.params.vae.seed == 3 and a4.params.vae.seed == 4 and c3.params.vae.feature_weight == 2
    assert a3.params.vae.out_dir == a3.params.ppo.encoder_dir == b3.params.ppo.encoder_dir  # one encoder per recipe
    assert Path(a3.params.vae.out_dir).parent == tmp_path / "data" / "g" / "encoders"
    assert Path(a3.params.vae.report_dir).parent == tmp_path / "reports" / "g" / "encoders"
    assert a3.encoder.startswith("seed3-") and a4.encoder.startswith("seed4-") and c3.encoder.startswith("seed3-")
    assert a3.encoder[6:] == a4.encoder[6:] != c3.encoder[6:]  # the recipe's hash, whatever the seed
    plain = {t.name: t for t in expand(load_params(ROOT / "params.yaml", sets(
        tmp_path, "sweep.name=g", "sweep.seeds=[3, 4]", "sweep.conditions={a: [], b: [ppo.blind=true]}")))}
    assert plain["a-seed3"].encoder is None and plain["a-seed3"].params.ppo.encoder_dir == "data/models/vae"
    assert a3.key != plain["a-seed3"].key  # another encoder, another trial
    with pytest.raises(ConfigError, match=r"'c': vae\.feature_weight changes nothing unless each trial trains its "
                                          r"encoder \(--train-encoder"):
        expand(load_params(ROOT / "params.yaml", sets(tmp_path, *args)))
    missing = load_params(ROOT / "params.yaml", sets(tmp_path, *args, "sweep.train_encoder=true",
                                                     f"vae.data_dir={tmp_path / 'no-rollouts'}"))
    with pytest.raises(ConfigError, match=r"vae\.data_dir .*no-rollouts: no such folder"):
        run_sweep(missing, "hexpipe sweep (test)", cpus=1, show_progress=False)  # before Ray starts
    assert not (tmp_path / "reports" / "g").exists()
    for key in ("vae.seed=1", "ppo.encoder_dir=x", "vae.out_dir=x"):
        owned = load_params(ROOT / "params.yaml", ["sweep.train_encoder=true", f"sweep.conditions={{a: [{key}]}}"])
        with pytest.raises(ConfigError, match=rf"'a': {key.split('=')[0]} is set by the sweep"):
            expand(owned)


def test_eta_and_time_format():
    assert eta_seconds([], 3, 2) is None and eta_seconds([10.0], 0, 2) == 0.0
    assert eta_seconds([10.0, 20.0], 3, 2) == 30.0  # 15 s a trial, 3 trials two at a time: two rounds
    assert format_seconds(75) == "1:15" and format_seconds(3725) == "1:02:05" and format_seconds(None) == "?"


def test_tiny_sweep_on_local_ray_records_a_failed_trial_and_goes_on(tmp_path, ray_env):
    model = ConvVAE(in_channels=1, image_size=64, latent_dim=8)  # an untrained encoder, as in test_evaluate
    export_encoder(model, tmp_path / "vae", encoder_config(model, "heightmap", (32, 32)))
    conditions = {"seeing": [f"ppo.encoder_dir={tmp_path / 'vae'}"], "blind": ["ppo.blind=true"],
                  "broken": [f"ppo.encoder_dir={tmp_path / 'no-encoder'}"]}
    params = load_params(ROOT / "params.yaml", sets(tmp_path, "sweep.name=tiny", "sweep.seeds=[0, 1]",
                                                    f"sweep.conditions={json.dumps(conditions)}"))
    lines: list[str] = []
    outcome, out = run_sweep(params, "hexpipe sweep (test)", cpus=2, show_progress=False, log=lines.append)
    assert sorted(outcome.ran) == ["blind-seed0", "blind-seed1", "seeing-seed0", "seeing-seed1"]
    assert sorted(outcome.failures) == ["broken-seed0", "broken-seed1"]
    failure = json.loads((out / "broken-seed0" / "failure.json").read_text())
    assert failure["error"].startswith("EncoderError") and "no-encoder" in failure["error"]
    assert "\n" not in failure["error"], repr(failure["error"])
    assert "hexpipe/sweep/trial.py" in failure["traceback"]
    assert any("broken-seed1 failed: EncoderError" in line for line in lines)

    record = json.loads((out / "seeing-seed1" / "result.json").read_text())
    assert record["status"] == "ok" and record["seed"] == 1 and record["node"]
    assert record["selection"]["chosen_seed"] == 1 and record["selection"]["candidates"]["1"]["episodes"] == 2
    assert "ip=127.0.0.1" in failure["traceback"]  # the local cluster stays on loopback
    assert {e["controller"] for e in record["episodes"]} == {"policy", "best_fixed", "reflex_gait", "open_loop"}
    assert (tmp_path / "data" / "tiny" / "seeing-seed1" / "ppo" / "policy" / "model.zip").is_file()
    assert (out / "seeing-seed1" / "eval" / "metrics.json").is_file()

    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["trials"] == {"complete": 4, "failed": 2, "total": 6}
    assert sorted(metrics["conditions"]) == ["blind", "seeing"]  # broken has no results
    cell = metrics["conditions"]["blind"]["single_block"]
    assert cell["seeds"] == 2 and cell["episodes"] == 2 and 0 <= cell["success_rate_low"] <= cell["success_rate_high"]
    assert "blind_vs_seeing" in metrics["improvement"]
    text = (out / "report.md").read_text()
    assert "broken-seed0 | failed" in text and "EncoderError" in text and "2 of 6 trials have no result" in text
    trials = (out / "trials.csv").read_text()
    assert trials.count(",ok,") == 4 and trials.count(",failed,") == 2


def test_a_sweep_that_trains_encoders_shares_one_between_conditions(tmp_path, ray_env):
    from test_vae import _write_rollouts, synthetic_frames

    _write_rollouts(tmp_path / "rollouts", synthetic_frames(episodes=4, steps=8))
    # "longer" needs the same encoder as "seeing"; with 2 CPUs the two may train it at once: the lock serialises them
    # (through the CLI in its own process: one process cannot start a second local Ray cluster after the first)
    args = [*HEXPIPE, "sweep", *cli_args(tmp_path, "--name", "enc", "--seeds", "1", "--train-encoder", "--cpus", "2",
                                         "--condition", "seeing:", "--condition", "longer:ppo.n_epochs=2",
                                         "--condition", "heavier:vae.feature_weight=2")]
    args += [a for s in (f"vae.data_dir={tmp_path / 'rollouts'}", "vae.epochs=1", "vae.batch_size=16")
             for a in ("--set", s)]
    run = subprocess.run(args, cwd=ROOT, env=ray_env, capture_output=True, text=True, timeout=300,
                         start_new_session=True)
    assert run.returncode == 0, run.stderr[-3000:]
    out = tmp_path / "reports" / "enc"
    names = ["heavier-seed1", "longer-seed1", "seeing-seed1"]
    records = {name: json.loads((out / name / "result.json").read_text()) for name in names}
    encoders = {name: record["vae"]["encoder"] for name, record in records.items()}
    assert encoders["seeing-seed1"] == encoders["longer-seed1"] != encoders["heavier-seed1"]
    made = sorted(p.parent.name for p in (tmp_path / "data" / "enc" / "encoders").glob("*/encoder.pt"))
    assert made == sorted(set(encoders.values()))
    config = json.loads((tmp_path / "data" / "enc" / "encoders" / encoders["seeing-seed1"] / "encoder.json")
                        .read_text())
    assert config["seed"] == 1
    for record in records.values():
        assert "probe/rise_distance_r2" in record["vae"] and record["seconds"]["vae"] > 0  # nan on 4 tiny episodes
    assert (out / "encoders" / encoders["heavier-seed1"] / "metrics.json").is_file()
    text = (out / "report.md").read_text()
    assert "| trial | encoder | distance R² | height R² | status |" in text
    assert f"| seeing-seed1 | `{encoders['seeing-seed1']}` | " in text
    assert "also trains its own encoder with `vae.seed`" in text


def _wait_for(predicate, timeout: float, proc: subprocess.Popen | None = None) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if proc is not None and proc.poll() is not None:
            raise AssertionError(f"exited early with {proc.returncode}")
        if time.monotonic() > deadline:
            raise AssertionError("timed out")
        time.sleep(0.2)


def _kill_group(proc: subprocess.Popen) -> None:
    """SIGKILL the process group this test started (the driver and the local Ray processes it spawned)."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)


def test_a_rerun_after_kill_9_of_the_driver_skips_the_completed_trials(tmp_path, ray_env):
    args = [*HEXPIPE, "sweep", *cli_args(tmp_path, "--name", "resume", "--seeds", "0,1", "--condition",
                                         "blind:ppo.blind=true", "--cpus", "1")]
    out = tmp_path / "reports" / "resume"
    proc = subprocess.Popen(args, cwd=ROOT, env=ray_env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            start_new_session=True)
    try:
        _wait_for(lambda: (out / "blind-seed0" / "result.json").is_file(), timeout=180, proc=proc)
        os.kill(proc.pid, signal.SIGKILL)  # the driver dies mid-sweep; the second trial is running or queued
    finally:
        _kill_group(proc)  # then what it left behind (Ray's agents outlive their driver)
    first = (out / "blind-seed0" / "result.json").read_text()
    assert not (out / "blind-seed1" / "result.json").exists() and not (out / "metrics.json").exists()

    rerun = subprocess.run(args, cwd=ROOT, env=ray_env, capture_output=True, text=True, timeout=240,
                           start_new_session=True)
    assert rerun.returncode == 0, rerun.stderr[-3000:]
    assert "1 of 2 trials already complete, skipped" in rerun.stderr
    assert "blind-seed1 done" in rerun.stderr and "blind-seed0 done" not in rerun.stderr
    assert (out / "blind-seed0" / "result.json").read_text() == first  # kept, not rerun
    assert json.loads((out / "metrics.json").read_text())["trials"] == {"complete": 2, "failed": 0, "total": 2}
    assert not list(out.rglob(".*.tmp*"))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_two_node_loopback_cluster(tmp_path, ray_env):
    """`ray start --head` and a second `ray start --address` on 127.0.0.1, one CPU each; the sweep joins them."""
    env = {**ray_env, "RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": secrets.token_hex(16)}  # the nodes and the driver
    port = _free_port()
    ray_bin = str(Path(sys.executable).with_name("ray"))
    node = ["--node-ip-address=127.0.0.1", "--num-cpus=1", "--block", "--disable-usage-stats"]
    head_cmd = [ray_bin, "start", "--head", f"--port={port}", "--include-dashboard=false", *node]
    nodes: list[subprocess.Popen] = []
    try:
        for i, cmd in enumerate([head_cmd, [ray_bin, "start", f"--address=127.0.0.1:{port}", *node]]):
            log = tmp_path / f"node{i}.log"
            nodes.append(subprocess.Popen(cmd, env=env, stdout=log.open("w"), stderr=subprocess.STDOUT,
                                          start_new_session=True))
            _wait_for(lambda log=log: "Ray runtime started" in log.read_text(), timeout=90, proc=nodes[-1])
        result = subprocess.run(
            [*HEXPIPE, "sweep", *cli_args(tmp_path, "--name", "two", "--seeds", "0,1", "--condition",
                                          "blind:ppo.blind=true", "--address", f"127.0.0.1:{port}")],
            cwd=ROOT, env=env, capture_output=True, text=True, timeout=240)
    finally:
        for proc in nodes:  # like `ray stop`, but only for the two nodes this test started
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
        for proc in nodes:
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(timeout=20)
            _kill_group(proc)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "2 node(s), 2 CPUs" in result.stderr
    out = tmp_path / "reports" / "two"
    records = [json.loads((out / f"blind-seed{s}" / "result.json").read_text()) for s in (0, 1)]
    assert len({r["node"] for r in records}) == 2  # one CPU per node: the two trials ran one on each node
    assert json.loads((out / "metrics.json").read_text())["trials"]["complete"] == 2
