"""The stride reflex's premise on a held gait: extra blocks walked at a 0.4, b 0.45, omega pi (a zero action), with
the stride reflex off and with it at 0.35, one episode per seed. Prints how each ended, the distance (m) and the base
positions (m) between which the legs swung with the short stride.

    .venv/bin/python reports/experiments/stride_reflex/premise.py [--seeds 30]
"""

from __future__ import annotations

import argparse

import numpy as np

from hexpipe.config import CpgConfig, TaskConfig
from hexpipe.envs.hexapod import HexapodEnv

GAIT = (0.4, 0.45, 3.141593)


def walk(seed: int, cap: float) -> tuple[str, float, tuple[float, float] | None]:
    """How the episode ended, its distance (m), and the first and last base x (m) at a stride shorter than a."""
    task = TaskConfig(sensors=(), stride_reflex=cap)
    env = HexapodEnv("extra_blocks", cpg=CpgConfig().holding(GAIT), initial_cpg=GAIT, task=task)
    env.reset(seed=seed)
    short = []
    try:
        while True:
            _, _, terminated, truncated, info = env.step(np.zeros(3))
            if info["stride"] < GAIT[0] - 1e-3:
                short.append(float(env.robot.base_state()[0][0]))
            if terminated or truncated:
                span = (round(min(short), 2), round(max(short), 2)) if short else None
                return info["termination"] or "time_limit", round(info["distance"], 2), span
    finally:
        env.close()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=30)
    seeds = range(ap.parse_args().seeds)
    crossed = {0.0: 0, 0.35: 0}
    print("seed  reflex off (end, m)  reflex at 0.35 (end, m, short stride from-to m)")
    for seed in seeds:
        off, on = walk(seed, 0.0), walk(seed, 0.35)
        crossed[0.0] += off[0] == "goal"
        crossed[0.35] += on[0] == "goal"
        print(f"{seed:4d}  {off[0]:>6} {off[1]:5.2f}        {on[0]:>6} {on[1]:5.2f} {on[2]}")
    print(f"crossed: {crossed[0.0]} of {len(seeds)} without the reflex, {crossed[0.35]} of {len(seeds)} with it")


if __name__ == "__main__":
    main()
