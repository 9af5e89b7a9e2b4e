"""Where the feet are along x relative to the body (m), per leg: what the lift-free zone has to span.

Usage: python reports/experiments/lift_zone/feet.py [--gait A B OMEGA] [--steps 60]

Holds one gait on flat ground and prints each leg's min and max foot x minus the base's x over `steps` control
steps, after 20 to settle. The hind feet are what a zone's `behind` must reach past a face; the front feet, what its
`ahead` must lead by if the lift is to rise before they meet the face.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from hexpipe.config import CpgConfig, TaskConfig
from hexpipe.envs.hexapod import HexapodEnv


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gait", type=float, nargs=3, default=(0.25, 0.4, 1.5 * math.pi), metavar=("A", "B", "OMEGA"))
    parser.add_argument("--steps", type=int, default=60)
    args = parser.parse_args()
    gait = tuple(args.gait)
    env = HexapodEnv("flat", cpg=CpgConfig().holding(gait), initial_cpg=gait, task=TaskConfig(sensors=()))
    env.reset(seed=0)
    rel = []
    for i in range(20 + args.steps):
        env.step(np.zeros(3))
        if i >= 20:
            rel.append(env.robot.foot_positions()[:, 0] - env.robot.base_state()[0][0])
    env.close()
    rel = np.array(rel)
    names = [leg.name for leg in env.robot_spec.legs]
    print(f"gait a={gait[0]:.3f} b={gait[1]:.3f} omega={gait[2]:.3f}: foot x - base x (m) over {args.steps} steps")
    for name, lo, hi in zip(names, rel.min(0), rel.max(0), strict=True):
        print(f"  {name:10s} {lo:+.2f} to {hi:+.2f}")


if __name__ == "__main__":
    main()
