"""Both sides of a verdict across sweeps: each sweep's mean success, time to goal and cost of transport (over the
successes) for the policy and for its best fixed gait, by terrain, from the sweeps' episodes.csv. Shows which side a
change moved: a reflex in the env moves the fixed gait too.

    .venv/bin/python reports/experiments/near_lift/both_sides.py reports/sweeps/stride_reflex reports/sweeps/stride_lift
        [--terrain single_block ...]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("sweeps", nargs="+")
    ap.add_argument("--terrain", dest="terrains", action="append")
    a = ap.parse_args()
    frames = []
    for sweep in a.sweeps:
        path = Path(sweep) / "episodes.csv"
        if not path.is_file():
            raise SystemExit(f"error: {path} not found (a sweep's report folder holds it)")
        frames.append(pd.read_csv(path).assign(sweep=Path(sweep).name))
    rows = pd.concat(frames)
    rows = rows[rows["controller"].isin(["policy", "best_fixed"])]
    if a.terrains:
        unknown = sorted(set(a.terrains) - set(rows["terrain"]))
        if unknown:
            raise SystemExit(f"error: terrain {unknown[0]!r} is in none of the sweeps")
        rows = rows[rows["terrain"].isin(a.terrains)]
    keys = ["terrain", "controller", "sweep"]
    table = rows.groupby(keys).agg(success=("success", "mean"), episodes=("success", "size")).join(
        rows[rows["success"].astype(bool)].groupby(keys)[["time", "cost_of_transport"]].mean())
    print(table.round(3).to_string())


if __name__ == "__main__":
    main()
