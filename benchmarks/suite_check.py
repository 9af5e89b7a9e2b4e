"""Is the evaluation suite physically meaningful? Fixed open-loop gaits (zero action) on every suite terrain: a
terrain that needs a lift must stop the low gait and let a high one through. Writes one row per episode.

Usage: python benchmarks/suite_check.py [--seeds 3] [--terrains flat,tall_block,...] [--heights 0.13,0.14]
                                       [--out reports/suite_check.json]

--heights adds a single_block-like block (face at 1.0 m, 0.3 m deep) of each height (m): how tall a block the
fixed gaits still cross.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from fixed_gait import fixed_gait_episode

from hexpipe.sim.terrain import load_terrain, parse_recipe

TERRAINS = ["flat", "low_block", "single_block", "tall_block", "steps_up", "block_near", "block_far"]
# (a, b) at omega = 1.5 pi: the paper's low initial gait (cpg.initial before 89e3243), a medium lift, b = 0.4,
# and the grid's best fixed gait
GAITS = [(0.25, 0.15), (0.4, 0.25), (0.4, 0.4), (0.4, 0.5)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--terrains", default=",".join(TERRAINS))
    parser.add_argument("--heights", default="", help="comma-separated block heights (m) to add")
    parser.add_argument("--out", type=Path, default=Path("reports/suite_check.json"))
    args = parser.parse_args()
    terrains = [load_terrain(t) for t in args.terrains.split(",") if t]
    terrains += [parse_recipe({"name": f"block_{h}", "boxes": [{"face": 1.0, "depth": 0.3, "height": float(h)}]})
                 for h in args.heights.split(",") if h]
    rows = []
    for terrain in terrains:
        for a, b in GAITS:
            runs = [fixed_gait_episode(terrain, a, b, s) for s in range(args.seeds)]
            rows += runs
            goals = [r for r in runs if r["termination"] == "goal"]
            where = ", ".join(f"{r['termination']} {r['distance_m']:.2f} m" for r in runs if r not in goals)
            times = "-".join(f"{t:.1f}" for t in sorted({min(r["time_s"] for r in goals),
                                                          max(r["time_s"] for r in goals)})) if goals else ""
            print(f"{terrain.name:12s} a={a:.2f} b={b:.2f}: {len(goals)}/{len(runs)} reach the goal"
                  + (f" in {times} s" if goals else "") + (f"; {where}" if where else ""), flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(rows, indent=2) + "\n")


if __name__ == "__main__":
    main()
