"""How high a fixed gait must lift to cross each terrain: success of constant gaits on evaluate's episodes.

    .venv/bin/python reports/experiments/ceiling/fixed_gaits.py --episodes 10 0.4,0.5,3.141593 0.4,0.6,3.141593 \
        [--terrains extra_blocks,tall_block] [--set section.key=value ...]

Each GAIT is a,b,omega (rad, rad, rad/s), held for the whole episode (evaluate's `best_fixed` controller); the
episodes are evaluate's (seeds eval.seed onwards), so a gait's row is what `best_fixed` would score with it. The
CPG's ceiling is raised to b 0.8 at run time (`cpg.upper`) so gaits above today's 0.5 can be held at all. Prints
success per gait and terrain, the cost of transport and the time to goal (s) of the successes per gait and terrain,
and on flat ground both averaged per gait.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

import pandas as pd
from episodes import checked_inputs, evaluate_episode, parse_gait  # the helper beside this script

from hexpipe.evaluation.controllers import ControllerSpec

SUITE = ("flat", "single_block", "extra_blocks", "wide_block", "rough", "low_block", "tall_block", "steps_up",
         "block_near", "block_far")
RAISED = "cpg.upper=[0.4,0.8,6.283185]"


def _one(job: tuple[tuple[float, float, float], str, int, tuple[str, ...]]) -> dict:
    gait, terrain, index, overrides = job
    row = evaluate_episode(ControllerSpec("best_fixed", gait=gait), terrain, index, overrides)
    name = f"a={gait[0]:.2f} b={gait[1]:.2f} omega={gait[2]:.2f}"
    return {"gait": name, "terrain": terrain, "success": bool(row["success"]),
            "cost_of_transport": row["cost_of_transport"], "time": row["time"]}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("gaits", nargs="+", metavar="A,B,OMEGA")
    ap.add_argument("--episodes", type=int, default=10)
    ap.add_argument("--terrains", default=",".join(SUITE))
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    gaits = [parse_gait(g) for g in a.gaits]
    terrains = a.terrains.split(",")
    overrides = (RAISED, *a.overrides)
    checked_inputs(overrides, terrains)
    jobs = [(g, t, i, overrides) for g in gaits for t in terrains for i in range(a.episodes)]
    with ProcessPoolExecutor(a.workers) as pool:
        frame = pd.DataFrame(list(pool.map(_one, jobs)))
    with pd.option_context("display.width", 250):
        print(f"success over {a.episodes} episodes a terrain (seeds from eval.seed)")
        print(frame.pivot_table(index="gait", columns="terrain", values="success", sort=False).round(2).to_string())
        arrived = frame[frame.success]
        print("\ncost of transport of the successes")
        print(arrived.pivot_table(index="gait", columns="terrain", values="cost_of_transport", sort=False).round(2)
              .to_string())
        print("\ntime to goal of the successes (s)")
        print(arrived.pivot_table(index="gait", columns="terrain", values="time", sort=False).round(2).to_string())
        flat = frame[(frame.terrain == "flat") & frame.success]
        if len(flat):
            print("\nflat ground, successes: cost of transport and time to goal (s)")
            print(flat.groupby("gait", sort=False)[["cost_of_transport", "time"]].mean().round(2).to_string())


if __name__ == "__main__":
    main()
