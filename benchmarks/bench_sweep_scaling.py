"""How `hexpipe sweep` scales with cores: N trials at once against one trial alone, on the same machine.

Issue 11 asks for the scaling on a machine with more cores (16, say). Both runs go through the CLI on a fresh local
Ray cluster of `--cpus` CPUs, with the trials of benchmarks/bench_sweep.py (blind PPO, so no encoder is needed;
2 envs and 2 eval workers, so each trial reserves 2 CPUs):

1. one trial alone: its wall time is the baseline, T1;
2. `--trials` trials (default cpus / 2, so every CPU is reserved): wall time TN.

speedup = N * T1 / TN (ideal: N), efficiency = speedup / N. The trials' own times inside each sweep show how much
each trial slows when the machine is full (memory bandwidth, turbo), apart from Ray's start and report.

    python benchmarks/bench_sweep_scaling.py --cpus 16                # 1 trial, then 8 at once
    python benchmarks/bench_sweep_scaling.py --cpus 2 --trials 1       # a smoke run on a small machine
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_sweep import ROOT, trial_overrides

from hexpipe.atomic import write_json

CPUS_PER_TRIAL = 2  # ppo.n_envs and eval.workers in trial_overrides


def run_sweep(trials: int, steps: int, cpus: int, scratch: Path) -> dict:
    """Run one sweep of `trials` blind trials through the CLI; its wall time and the trials' own times (s)."""
    sets = trial_overrides(steps, trials, scratch)
    cmd = [sys.executable, "-m", "hexpipe.cli", "sweep", "--cpus", str(cpus)]
    cmd += [a for s in sets for a in ("--set", s)]
    ray_tmp = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths must fit 107 bytes
    env = {**os.environ, "RAY_TMPDIR": ray_tmp, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get(
        "PYTHONPATH", "")]).rstrip(os.pathsep)}
    try:
        started = time.perf_counter()
        subprocess.run(cmd, cwd=ROOT, env=env, check=True)
        wall = time.perf_counter() - started
    finally:
        shutil.rmtree(ray_tmp, ignore_errors=True)
    own = [json.loads(path.read_text())["seconds"]["total"]
           for path in sorted((scratch / "reports/bench").glob("*/result.json"))]
    if len(own) != trials:
        raise SystemExit(f"bench_sweep_scaling: {len(own)} of {trials} trials finished in {scratch}")
    return {"trials": trials, "wall_seconds": round(wall, 2), "trial_seconds": [round(s, 2) for s in own],
            "trial_median_seconds": round(statistics.median(own), 2)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cpus", type=int, default=os.cpu_count() or 2, help="CPUs of the local Ray cluster")
    parser.add_argument("--trials", type=int, default=0, help="trials at once (default: cpus / 2)")
    parser.add_argument("--steps", type=int, default=8192, help="PPO steps per trial")
    parser.add_argument("--out", type=Path, default=ROOT / "reports/bench/sweep_scaling.json")
    args = parser.parse_args()
    trials = args.trials or max(1, args.cpus // CPUS_PER_TRIAL)
    scratch = Path(tempfile.mkdtemp(prefix="bench-scaling-"))
    try:
        alone = run_sweep(1, args.steps, args.cpus, scratch / "one")
        print(f"one trial alone: {alone['wall_seconds']:.1f} s", flush=True)
        together = run_sweep(trials, args.steps, args.cpus, scratch / "many")
        print(f"{trials} trials at once: {together['wall_seconds']:.1f} s", flush=True)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    speedup = trials * alone["wall_seconds"] / together["wall_seconds"]
    result = {
        "cpus": args.cpus, "machine_cpus": os.cpu_count(), "cpus_per_trial": CPUS_PER_TRIAL,
        "steps_per_trial": args.steps, "python": sys.version.split()[0],
        "one_trial": alone, "n_trials": together,
        "speedup": round(speedup, 2), "efficiency": round(speedup / trials, 3),
        "trial_slowdown_when_full": round(together["trial_median_seconds"] / alone["trial_median_seconds"], 3),
        "command": f"python benchmarks/bench_sweep_scaling.py --cpus {args.cpus} --trials {trials} "
                   f"--steps {args.steps}",
    }
    write_json(args.out, result)
    print(f"{trials} trials in {together['wall_seconds']:.1f} s against one in {alone['wall_seconds']:.1f} s: "
          f"speedup {speedup:.2f}x of {trials} (efficiency {speedup / trials:.0%}); wrote {args.out}")


if __name__ == "__main__":
    main()
