"""What the lift-free zone (`task.lift_free_zone`) costs on the hot path: env.step with it, without it, and the
zone's check alone.

Usage: python benchmarks/bench_lift_free.py [--windows 9] [--steps 100] [--terrain single_block]

Three envs, the default config each but for the lift price and its zone (off; on at [0.4, 0.5] m; the price alone,
the default's hot path), stepped with the same seeded random actions in interleaved windows on one core; medians
are compared, so machine noise hits all alike. The check itself (one `Terrain.relief` over a 19 x 3 strip) is also
timed directly, which is the sharper number: an env step is mostly physics.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
import timeit

import numpy as np

from hexpipe.config import TaskConfig
from hexpipe.envs.hexapod import HexapodEnv

ZONES = {"zone on": (10.0, (0.4, 0.5)), "zone off": (10.0, None), "no price": (0.0, None)}


def window(env: HexapodEnv, rng: np.random.Generator, steps: int) -> float:
    start = time.perf_counter()
    for _ in range(steps):
        *_, terminated, truncated, _ = env.step(rng.uniform(-1.0, 1.0, 3))
        if terminated or truncated:
            env.reset()
    return (time.perf_counter() - start) / steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--windows", type=int, default=9)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--terrain", default="single_block")
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    envs = {name: HexapodEnv(args.terrain, task=TaskConfig(sensors=(), lift_cost=cost, lift_free_zone=zone))
            for name, (cost, zone) in ZONES.items()}
    rngs = {name: np.random.default_rng(0) for name in ZONES}
    for env in envs.values():
        env.reset(seed=0)
    times: dict[str, list[float]] = {name: [] for name in ZONES}
    for _ in range(args.windows):
        for name in ZONES:
            times[name].append(window(envs[name], rngs[name], args.steps))
    step_ms = {name: 1e3 * statistics.median(t) for name, t in times.items()}
    base = step_ms["no price"]
    print(f"env.step on {args.terrain}, medians of {args.windows} windows of {args.steps} steps:")
    for name, ms in step_ms.items():
        print(f"  {name:9s} {ms:.3f} ms ({100 * (ms / base - 1):+.1f}% against no price)")
    for name, env in envs.items():
        pos, quat, *_ = env.robot.base_state()
        check = min(timeit.repeat(lambda env=env, pos=pos, quat=quat: env._lift_free(pos, quat), number=2000,
                                  repeat=5)) / 2000
        print(f"  the zone's check alone, {name}: {1e6 * check:.1f} us a step")


if __name__ == "__main__":
    main()
