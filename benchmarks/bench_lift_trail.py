"""What the following lift (`cpg.lift_follows`) costs on the hot path: env.step with it vs without.

Usage: python benchmarks/bench_lift_trail.py [--windows 9] [--steps 100] [--terrain flat]

Two envs, the default config each but for the setting, stepped with the same seeded random actions in interleaved
windows on one core; medians are compared, so machine noise hits both alike. The trail grows with the episode (one
sample per control step, at most 800 at the 40 s limit), so the windows run through whole episodes.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from hexpipe.config import CpgConfig, TaskConfig
from hexpipe.envs.hexapod import HexapodEnv


def window(env: HexapodEnv, rng: np.random.Generator, steps: int) -> float:
    start = time.perf_counter()
    for _ in range(steps):
        *_, terminated, truncated, _ = env.step(rng.uniform(-1.0, 1.0, 3))
        if terminated or truncated:
            env.reset()
    return (time.perf_counter() - start) / steps


def interleaved_step_ms(envs: dict[str, HexapodEnv], windows: int, steps: int) -> dict[str, float]:
    """Median ms per env.step of each env, timed in interleaved windows on one core with the same seeded random
    actions, so that machine noise hits every env alike. Also used by bench_lift_free.py."""
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    rngs = {name: np.random.default_rng(0) for name in envs}
    for env in envs.values():
        env.reset(seed=0)
    times: dict[str, list[float]] = {name: [] for name in envs}
    for _ in range(windows):
        for name, env in envs.items():
            times[name].append(window(env, rngs[name], steps))
    return {name: 1e3 * statistics.median(t) for name, t in times.items()}


def arguments(description: str, terrain: str) -> argparse.Namespace:
    """The benchmarks' shared options: --windows, --steps and --terrain."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--windows", type=int, default=9)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--terrain", default=terrain)
    return parser.parse_args()


def main() -> None:
    args = arguments(__doc__.splitlines()[0], "flat")
    envs = {name: HexapodEnv(args.terrain, cpg=CpgConfig(lift_follows=name == "with"), task=TaskConfig(sensors=()))
            for name in ("with", "without")}
    step_ms = interleaved_step_ms(envs, args.windows, args.steps)
    with_ms, without_ms = step_ms["with"], step_ms["without"]
    print(f"env.step on {args.terrain}: {with_ms:.3f} ms with the following lift, {without_ms:.3f} ms without "
          f"({100 * (with_ms / without_ms - 1):+.1f}%; medians of {args.windows} windows of {args.steps} steps)")

if __name__ == "__main__":
    main()
