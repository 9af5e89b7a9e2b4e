"""What the reward pays a fixed gait over one of evaluate's episodes, term by term: does it prefer a longer stride?

    .venv/bin/python reports/experiments/time/return_terms.py --terrains flat --episodes 2 \
        0.4,0.2,3.141593 0.35,0.2,3.141593 0.3,0.2,3.141593 [--set task.time_cost=50]

Each GAIT is a,b,omega (rad, rad, rad/s), held for the whole episode (evaluate's `best_fixed` controller) within the
CPG's bounds in params.yaml. Prints, per gait and terrain, the mean time to goal (time_s), cost of transport, control
steps, each reward term's sum (`time` is task.time_cost's), the undiscounted return and the return per control
step (what a discount favours).
"""

from __future__ import annotations

import argparse
import sys
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ceiling"))
from episodes import checked_inputs, evaluate_episode, parse_gait  # the helper in ../ceiling

from hexpipe.evaluation.controllers import ControllerSpec


def _one(job: tuple[tuple[float, float, float], str, int, tuple[str, ...]]) -> dict:
    gait, terrain, index, overrides = job
    sums: dict[str, float] = defaultdict(float)
    steps = [0]

    def hook(env, reward, info, ended) -> None:
        for name, value in info.get("reward_terms", {}).items():
            sums[name] += value
        steps[0] += 1

    row = evaluate_episode(ControllerSpec("best_fixed", gait=gait), terrain, index, overrides, on_step=hook)
    return {"gait": f"a={gait[0]:.2f} b={gait[1]:.2f} omega={gait[2]:.2f}", "terrain": terrain,
            "success": float(row["success"]), "time_s": row["time"], "cost_of_transport": row["cost_of_transport"],
            "steps": steps[0] - 1, **sums}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("gaits", nargs="+", metavar="A,B,OMEGA")
    ap.add_argument("--episodes", type=int, default=2)
    ap.add_argument("--terrains", default="flat")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    gaits = [parse_gait(g) for g in a.gaits]
    terrains = a.terrains.split(",")
    checked_inputs(a.overrides, terrains)
    jobs = [(g, t, i, tuple(a.overrides)) for g in gaits for t in terrains for i in range(a.episodes)]
    with ProcessPoolExecutor(a.workers) as pool:
        frame = pd.DataFrame(list(pool.map(_one, jobs)))
    facts = ("gait", "terrain", "success", "time_s", "cost_of_transport", "steps")
    terms = [c for c in frame.columns if c not in facts]
    frame["return"] = frame[terms].sum(axis=1)
    frame["per_step"] = frame["return"] / frame["steps"]
    table = frame.groupby(["terrain", "gait"], sort=False).mean(numeric_only=True)
    with pd.option_context("display.width", 250, "display.max_columns", 30):
        print(f"means over {a.episodes} episodes a gait and terrain (seeds from eval.seed); overrides: "
              f"{' '.join(a.overrides) or 'none'}")
        print(table.round(2).to_string())


if __name__ == "__main__":
    main()
