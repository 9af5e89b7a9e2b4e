"""Fixed gaits on flat ground started turned off the course: the base's yaw every 2 s, with and without the heading
reflex. Shows whether a gait turns itself back, holds a heading, or drifts further.

    PYTHONPATH=. .venv/bin/python reports/experiments/heading/turned_start.py [--gain 0 --gain 1] \
        [--turn 0.4 --turn -0.4 --turn 1.0] [--steps 200] [GAIT ...]

Each GAIT is a,b,omega (rad, rad, rad/s), held by zero actions; the robot is reset as evaluate resets it (seed 0),
then its base is turned by TURN rad about z in place before the first step. "end N" marks an episode that ended at
step N (the 3 m goal, or stuck). Run from a checkout whose hexpipe has `sim.heading_gain` (branch heading).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "ceiling"))
from episodes import parse_gait  # the helper in ceiling/

from hexpipe.config import CpgConfig, SimConfig
from hexpipe.sensors.heightmap import quat_to_yaw

DEFAULT_GAITS = ("0.4,0.4,3.141593", "0.6,0.5,3.141593", "0.6,0.5,4.712389", "0.6,0.2,3.926991")


def yaw_trace(gait: tuple[float, float, float], gain: float, turn: float, steps: int) -> list[str]:
    import pybullet as p

    from hexpipe.envs.hexapod import HexapodEnv

    cpg = CpgConfig(lower=[0.05, 0.05, 1.0], upper=[0.8, 0.8, 6.0], initial=list(gait))
    env = HexapodEnv(terrain="flat", sim=SimConfig(heading_gain=gain), cpg=cpg)
    out = []
    try:
        env.reset(seed=0)
        pos = env.robot.base_state()[0]
        p.resetBasePositionAndOrientation(env.robot.body, pos, p.getQuaternionFromEuler([0.0, 0.0, turn]),
                                          physicsClientId=env.client)
        for step in range(1, steps + 1):
            _, _, terminated, truncated, _ = env.step(np.zeros(3))
            if step % 40 == 0:
                out.append(f"{quat_to_yaw(env.robot.base_state()[1]):+.2f}")
            if terminated or truncated:
                out.append(f"end {step}")
                break
    finally:
        env.close()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("gaits", nargs="*", default=list(DEFAULT_GAITS), metavar="A,B,OMEGA")
    ap.add_argument("--gain", dest="gains", type=float, action="append")
    ap.add_argument("--turn", dest="turns", type=float, action="append")
    ap.add_argument("--steps", type=int, default=200)
    a = ap.parse_args()
    print("gait (a, b, omega) | turn (rad) | gain | yaw (rad) every 40 control steps (2 s)")
    for text in a.gaits:
        gait = parse_gait(text)
        for turn in a.turns or [0.4, -0.4, 1.0]:
            for gain in a.gains or [0.0, 1.0]:
                print(f"{text:>18} | {turn:+.1f} | {gain:g} | " + " ".join(yaw_trace(gait, gain, turn, a.steps)))


if __name__ == "__main__":
    main()
