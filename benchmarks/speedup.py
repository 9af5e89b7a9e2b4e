"""Env steps per second of this tree against an older commit, in alternating processes (old, new, old, new, ...).

Usage: python benchmarks/speedup.py [--old f9fd347] [--rounds 7] [--steps 200] [--out reports/bench/speedup.json]

The old commit is exported with `git archive` into a temporary folder (no worktree, nothing in .git changes). Each
round starts one process per tree with PYTHONPATH pointing at it; each process builds `HexapodEnv(terrain)` with its
tree's own defaults (the default config), pins itself to one core, warms up, and times `--steps` control steps with
zero and with seeded random actions on each terrain. Alternating processes spreads the machine's noise over both
trees; the report gives per-case medians over the rounds and the ratio of medians (old ms per step / new).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# Runs inside each tree's process; uses only the env API that every commit has.
TIMER = """
import json, os, sys, time
import numpy as np
from hexpipe.envs.hexapod import HexapodEnv
if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
steps, terrains = int(sys.argv[1]), sys.argv[2].split(",")
out = {}
for terrain in terrains:
    env = HexapodEnv(terrain)
    for mode in ("zero", "random"):
        rng = np.random.default_rng(0)
        env.reset(seed=0)
        actions = np.zeros((steps, 3)) if mode == "zero" else rng.uniform(-1, 1, (steps, 3))
        for a in actions[:20]:
            env.step(a)
        env.reset(seed=0)
        start = time.perf_counter()
        for a in actions:
            *_, terminated, truncated, _ = env.step(a)
            if terminated or truncated:
                env.reset()
        out[f"{terrain}/{mode}"] = 1e3 * (time.perf_counter() - start) / steps
    env.close()
print(json.dumps(out))
"""


def export_commit(commit: str, folder: Path) -> str:
    """Write the tree of `commit` into `folder`; returns the full hash."""
    full = subprocess.run(["git", "rev-parse", commit], cwd=ROOT, check=True, capture_output=True, text=True)
    archive = subprocess.run(["git", "archive", full.stdout.strip()], cwd=ROOT, check=True, capture_output=True)
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive.stdout, check=True)
    return full.stdout.strip()


def time_tree(tree: Path, steps: int, terrains: str) -> dict[str, float]:
    env = os.environ | {"PYTHONPATH": str(tree)}
    done = subprocess.run([sys.executable, "-c", TIMER, str(steps), terrains], env=env, cwd=tree, check=True,
                          capture_output=True, text=True, timeout=600)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--old", default="f9fd347", help="the commit to compare against")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--steps", type=int, default=200, help="control steps per case and process")
    parser.add_argument("--terrains", default="flat,single_block")
    parser.add_argument("--out", type=Path, default=ROOT / "reports/bench/speedup.json")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    from hexpipe.atomic import write_json

    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, check=True, capture_output=True, text=True)
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT, check=True,
                           capture_output=True, text=True).stdout.strip() != ""
    with tempfile.TemporaryDirectory(prefix="hexpipe-old-") as tmp:
        old_commit = export_commit(args.old, Path(tmp))
        trees = {"old": Path(tmp), "new": ROOT}
        samples: dict[str, dict[str, list[float]]] = {"old": {}, "new": {}}
        for r in range(args.rounds):
            order = ("old", "new") if r % 2 == 0 else ("new", "old")
            for name in order:
                for case, ms in time_tree(trees[name], args.steps, args.terrains).items():
                    samples[name].setdefault(case, []).append(ms)
            print(f"round {r + 1}/{args.rounds}: " + ", ".join(
                f"{c} {samples['old'][c][-1]:.2f}/{samples['new'][c][-1]:.2f} ms" for c in samples["new"]),
                flush=True)

    cases = {}
    for case in samples["new"]:
        old_ms, new_ms = statistics.median(samples["old"][case]), statistics.median(samples["new"][case])
        cases[case] = {"old_ms_per_step": old_ms, "new_ms_per_step": new_ms, "old_steps_per_s": 1e3 / old_ms,
                       "new_steps_per_s": 1e3 / new_ms, "speedup": old_ms / new_ms,
                       "old_samples_ms": samples["old"][case], "new_samples_ms": samples["new"][case]}
    speedups = [c["speedup"] for c in cases.values()]
    report = {
        "command": "python benchmarks/speedup.py " + " ".join(sys.argv[1:]),
        "old_commit": old_commit, "new_commit": head.stdout.strip(), "new_tree_has_uncommitted_changes": dirty,
        "rounds": args.rounds, "steps_per_case": args.steps, "config": "each tree's default (HexapodEnv(terrain))",
        "cases": cases, "min_speedup": min(speedups), "median_speedup": statistics.median(speedups),
    }
    write_json(args.out, report)
    for case, c in cases.items():
        print(f"{case:20s} old {c['old_steps_per_s']:6.0f} steps/s, new {c['new_steps_per_s']:6.0f} steps/s: "
              f"{c['speedup']:.2f}x")
    print(f"median speedup {report['median_speedup']:.2f}x, min {report['min_speedup']:.2f}x; wrote {args.out}")


if __name__ == "__main__":
    main()
