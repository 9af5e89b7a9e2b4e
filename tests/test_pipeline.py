"""The whole pipeline at smoke size: `dvc repro` of all four stages in a scratch copy of the repo.

Run by hand with `.venv/bin/pytest tests/test_pipeline.py -s` (about two minutes on two cores).
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import yaml

from hexpipe.config import load_params

ROOT = Path(__file__).resolve().parents[1]
SMOKE = [
    "collect.episodes=3", "collect.max_seconds=3", "collect.workers=2",
    "vae.epochs=2", "vae.batch_size=32",
    "ppo.total_timesteps=256", "ppo.n_envs=2", "ppo.n_steps=64", "ppo.batch_size=64", "ppo.n_epochs=1",
    "ppo.checkpoint_every=128", "ppo.validation_episodes=2",
    "ppo.candidates=3",  # best of 3 (the default is 1 since `lift80_t150`): the selection path end to end
    "task.time_limit=3.0",
    "eval.terrains=[single_block, extra_blocks]", "eval.episodes=1", "eval.log_episodes=1",
    "eval.grid_a=[0.25]", "eval.grid_b=[0.4]", "eval.grid_omega=[4.7]",
]


def run(args: list[str], cwd: Path) -> str:
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    result = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, f"{' '.join(args)} failed:\n{result.stdout[-3000:]}\n{result.stderr[-3000:]}"
    return result.stdout + result.stderr


def scratch_repo(tmp_path: Path) -> Path:
    repo = tmp_path / "repo"
    repo.mkdir()
    for name in ("dvc.yaml", ".dvcignore", ".gitignore"):
        shutil.copy(ROOT / name, repo / name)
    shutil.copytree(ROOT / "hexpipe", repo / "hexpipe", ignore=shutil.ignore_patterns("__pycache__"))
    params = load_params(ROOT / "params.yaml", SMOKE).model_dump(mode="json")
    (repo / "params.yaml").write_text(yaml.safe_dump(params, sort_keys=False))
    run(["git", "init", "-q"], repo)
    run(["dvc", "init", "-q"], repo)
    run(["dvc", "config", "core.analytics", "false"], repo)
    run(["git", "add", "-A"], repo)  # dvclive needs a commit to exist, as in any clone
    identity = ["-c", "user.name=hexpipe-test", "-c", "user.email=test@hexpipe.invalid"]
    run(["git", *identity, "commit", "-qm", "smoke"], repo)
    return repo


def test_dvc_repro_runs_all_stages_then_nothing_then_only_what_changed(tmp_path):
    repo = scratch_repo(tmp_path)
    out = run(["dvc", "repro"], repo)
    for stage in ("collect", "train-vae", "train-ppo", "evaluate"):
        assert f"Running stage '{stage}'" in out
    assert (repo / "dvc.lock").is_file()
    table = json.loads((repo / "reports/eval/metrics.json").read_text())
    assert {k for k, v in table.items() if isinstance(v, dict)} == {"single_block", "extra_blocks"}
    assert table["verdict/policy/terrains"] == 2  # and the verdict, in flat numbers
    assert "policy" in table["single_block"] and "open_loop" in table["single_block"]
    assert (repo / "reports/README.md").read_text().count("not run yet") == 0
    assert (repo / "reports/ppo/training_curve.png").is_file()
    chosen = json.loads((repo / "reports/ppo/selection.json").read_text())  # best of 3 candidates
    assert sorted(chosen["candidates"]) == ["0", "1000", "2000"] and str(chosen["chosen_seed"]) in chosen["candidates"]
    summary = (repo / "reports/README.md").read_text()
    assert f"| {chosen['chosen_seed']} | " in summary and "| seed | validation return |" in summary
    played = run(["hexpipe", "play"], repo)  # after the pipeline, with no options: the policy it trained
    assert "play: policy from data/models/ppo on single_block, seed 1000" in played and "termination" in played

    again = run(["dvc", "repro"], repo)
    assert "Running stage" not in again
    stray = repo / "hexpipe/sim/__pycache__/terrain.cpython-311.pyc"  # bytecode differs per clone: not a dependency
    stray.parent.mkdir(exist_ok=True)
    stray.write_bytes(b"\x00bytecode")
    assert "Data and pipelines are up to date" in run(["dvc", "status"], repo)

    params = yaml.safe_load((repo / "params.yaml").read_text())
    params["ppo"]["learning_rate"] = 0.001
    (repo / "params.yaml").write_text(yaml.safe_dump(params, sort_keys=False))
    rerun = run(["dvc", "repro"], repo)
    ran = sorted(line.split("'")[1] for line in rerun.splitlines() if line.startswith("Running stage"))
    assert ran == ["evaluate", "train-ppo"]

    # killed in the middle of a stage, then run again: completes with no manual cleanup
    params["ppo"]["learning_rate"] = 0.002
    params["ppo"]["total_timesteps"] = 2048
    (repo / "params.yaml").write_text(yaml.safe_dump(params, sort_keys=False))
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    log = (tmp_path / "killed.log").open("w")
    proc = subprocess.Popen(["dvc", "repro"], cwd=repo, env=env, stdout=log, stderr=subprocess.STDOUT,
                            start_new_session=True)
    deadline = time.time() + 300
    while time.time() < deadline and not list((repo / "data/models/ppo").rglob("checkpoints/step-*")):
        time.sleep(0.1)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=60)
    finished = run(["dvc", "repro"], repo)
    assert "Running stage 'evaluate'" in finished
    assert run(["dvc", "status"], repo).strip().endswith("Data and pipelines are up to date.")

    metrics = run(["dvc", "metrics", "show", "--json"], repo)
    assert "reports/eval/metrics.json" in metrics and "reports/ppo/metrics.json" in metrics
    assert "reports/ppo/selection.json" in metrics
