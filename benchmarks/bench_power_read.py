"""What the energy accounting costs on the hot path: env.step with the per-substep joint-power read vs without.

Usage: python benchmarks/bench_power_read.py [--windows 9] [--steps 60]

Two envs on `single_block`, one with `Robot.mechanical_power` stubbed out, stepped in interleaved windows on one
core; medians are compared, so machine noise hits both alike.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from hexpipe.config import TaskConfig
from hexpipe.envs.hexapod import HexapodEnv


def reset(env: HexapodEnv, read_power: bool) -> None:
    env.reset()
    if not read_power:  # reset builds a new Robot: stub its power read each time
        env.robot.mechanical_power = lambda: 0.0


def window(env: HexapodEnv, steps: int, read_power: bool) -> float:
    start = time.perf_counter()
    for _ in range(steps):
        *_, terminated, truncated, _ = env.step(np.zeros(3))
        if terminated or truncated:
            reset(env, read_power)
    return (time.perf_counter() - start) / steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--windows", type=int, default=9)
    parser.add_argument("--steps", type=int, default=60)
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    envs = {name: HexapodEnv("single_block", task=TaskConfig(sensors=())) for name in ("with", "without")}
    for name, env in envs.items():
        env.reset(seed=0)
        reset(env, read_power=name == "with")
    times: dict[str, list[float]] = {name: [] for name in envs}
    for _ in range(args.windows):
        for name, env in envs.items():
            times[name].append(window(env, args.steps, read_power=name == "with"))
    with_ms, without_ms = (1e3 * statistics.median(times[n]) for n in ("with", "without"))
    print(f"env.step: {with_ms:.3f} ms with the power read, {without_ms:.3f} ms without "
          f"({100 * (with_ms / without_ms - 1):+.1f}%)")


if __name__ == "__main__":
    main()
