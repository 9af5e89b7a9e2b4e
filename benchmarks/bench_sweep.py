"""Ray's overhead in `hexpipe sweep`: a sweep's wall time against the sum of its trials' own times run one after
another (target: <= 1.1x on this 2-core machine).

Each trial reserves 2 CPUs (ppo.n_envs=2, eval.workers=2), so on 2 cores Ray runs the trials one after another, and
the ratio is Ray's cost: starting Python and the local cluster, the worker process's imports, scheduling, and the
sweep's statistics and report. Two denominators: the trials' own times as the sweep measured them (same moment,
same machine load: the headline), and the same trials run first one after another in this process (sensitive to
load that changes between the two phases on a shared machine). Blind policies: no encoder is needed.

    .venv/bin/python benchmarks/bench_sweep.py                      # 3 trials of 8192 steps
    .venv/bin/python benchmarks/bench_sweep.py --trials 4 --steps 4096 --out reports/bench/sweep_overhead.json
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hexpipe.atomic import write_json  # noqa: E402
from hexpipe.config import load_params  # noqa: E402
from hexpipe.sweep.grid import expand  # noqa: E402


def trial_overrides(steps: int, trials: int, folder: Path) -> list[str]:
    return [f"ppo.total_timesteps={steps}", "ppo.n_steps=512", "ppo.batch_size=128", "ppo.n_epochs=4",
            "ppo.n_envs=2", "eval.workers=2", "eval.terrains=[single_block]", "eval.episodes=2",
            "eval.grid_a=[0.4]", "eval.grid_b=[0.5]", "eval.grid_omega=[4.712389]",
            "sweep.name=bench", f"sweep.seeds=[{', '.join(map(str, range(trials)))}]",
            "sweep.conditions={blind: [ppo.blind=true]}", "sweep.resamples=1000",
            f"sweep.data_dir={folder / 'data'}", f"sweep.report_dir={folder / 'reports'}"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=3)
    parser.add_argument("--steps", type=int, default=8192, help="PPO steps per trial")
    parser.add_argument("--out", type=Path, default=ROOT / "reports/bench/sweep_overhead.json")
    args = parser.parse_args()
    scratch = Path(tempfile.mkdtemp(prefix="bench-sweep-"))
    ray_tmp = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths must fit 107 bytes
    try:
        # 1. the trials one after another, in this process
        from hexpipe.sweep.trial import run_trial

        sets = trial_overrides(args.steps, args.trials, scratch / "sequential")
        trials = expand(load_params(ROOT / "params.yaml", sets))
        sequential = []
        started = time.perf_counter()
        for trial in trials:
            t0 = time.perf_counter()
            run_trial(trial.params)
            sequential.append(time.perf_counter() - t0)
            print(f"sequential {trial.name}: {sequential[-1]:.1f} s", flush=True)
        sequential_wall = time.perf_counter() - started

        # 2. the same trials as a sweep on a local Ray cluster, through the CLI, timed from outside
        sets = trial_overrides(args.steps, args.trials, scratch / "sweep")
        cmd = [sys.executable, "-m", "hexpipe.cli", "sweep", "--cpus", "2"]
        cmd += [a for s in sets for a in ("--set", s)]
        env = {**os.environ, "RAY_TMPDIR": ray_tmp, "PYTHONPATH": str(ROOT)}
        started = time.perf_counter()
        subprocess.run(cmd, cwd=ROOT, env=env, check=True)
        sweep_wall = time.perf_counter() - started
        import json

        in_sweep = [json.loads((scratch / "sweep/reports/bench" / t.name / "result.json").read_text())["seconds"]
                    ["total"] for t in trials]
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
        shutil.rmtree(ray_tmp, ignore_errors=True)

    result = {
        "trials": args.trials, "steps_per_trial": args.steps, "cpus": 2, "cpus_per_trial": 2,
        "sequential_trial_seconds": [round(s, 2) for s in sequential],
        "sequential_sum_seconds": round(sum(sequential), 2), "sequential_process_seconds": round(sequential_wall, 2),
        "sweep_wall_seconds": round(sweep_wall, 2), "sweep_trial_seconds": [round(s, 2) for s in in_sweep],
        "sweep_trial_sum_seconds": round(sum(in_sweep), 2),
        "ratio_sweep_vs_own_trial_sum": round(sweep_wall / sum(in_sweep), 3),
        "ray_overhead_seconds": round(sweep_wall - sum(in_sweep), 2),
        "ratio_sweep_vs_sequential_run": round(sweep_wall / sum(sequential), 3),
        "command": " ".join([".venv/bin/python", "benchmarks/bench_sweep.py", "--trials", str(args.trials),
                             "--steps", str(args.steps)]),
    }
    write_json(args.out, result)
    print(f"sweep {sweep_wall:.1f} s vs its trials' own {sum(in_sweep):.1f} s: "
          f"{result['ratio_sweep_vs_own_trial_sum']:.3f}x (target <= 1.1); vs the sequential run "
          f"{sum(sequential):.1f} s: {result['ratio_sweep_vs_sequential_run']:.3f}x; wrote {args.out}")


if __name__ == "__main__":
    main()
