"""Where the stride reflex sees a straddle: a fixed gait walks each suite terrain and the reflex reads its height map.

    .venv/bin/python reports/experiments/straddle/where.py [--gait 0.4,0.45,3.141593] [--seeds 3] [--terrains ...]

For each terrain and seed (the env's reset seed), prints how the episode ended, how many control steps the zone
(task.lift_free_zone on the height map) held two raised regions or more (`hexpipe.sim.stride_reflex`), and the base's
x (m) from the first such step to the last. The CPG's ceiling is raised so that any gait can be held.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ceiling"))
from episodes import checked_inputs, parse_gait  # the helper in ../ceiling

from hexpipe.config import reflex_zone
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.sim.stride_reflex import raised_regions

SUITE = ("flat", "single_block", "extra_blocks", "wide_block", "rough", "low_block", "tall_block", "steps_up",
         "block_near", "block_far")


def walk(params, terrain: str, gait: tuple[float, float, float], seed: int) -> tuple[str, int, list[float]]:
    """(termination, steps, base x at every step the zone held a straddle) of one held-gait episode."""
    cpg = params.cpg.model_copy(update={"upper": (0.4, 0.8, 6.283185)}).holding(gait)
    env = HexapodEnv(terrain, params.sim, cpg, params.sensors, params.task, initial_cpg=gait)
    mask = reflex_zone(params.sensors, params.task.lift_free_zone)
    env.reset(seed=seed)
    xs: list[float] = []
    try:
        while True:
            _, _, terminated, truncated, info = env.step(np.zeros(3))
            if raised_regions(env.sense(["heightmap"])["heightmap"], mask) >= 2:
                xs.append(float(env.robot.base_state()[0][0]))
            if terminated or truncated:
                return str(info["termination"]), env.steps, xs
    finally:
        env.close()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--gait", default="0.4,0.45,3.141593", metavar="A,B,OMEGA")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--terrains", default=",".join(SUITE))
    a = ap.parse_args()
    terrains = a.terrains.split(",")
    params = checked_inputs([], terrains)
    gait = parse_gait(a.gait)
    print(f"gait a={gait[0]} b={gait[1]} omega={gait[2]}; a straddle: two regions raised > 5 cm in the zone")
    print(f"{'terrain':<14}{'seed':>5}  {'ended':<10}{'steps':>6}{'straddle':>9}  base x at a straddle (m)")
    for terrain in terrains:
        for seed in range(a.seeds):
            ended, steps, xs = walk(params, terrain, gait, seed)
            span = f"{min(xs):.2f}-{max(xs):.2f}" if xs else "-"
            print(f"{terrain:<14}{seed:>5}  {ended:<10}{steps:>6}{len(xs):>9}  {span}")


if __name__ == "__main__":
    main()
