"""What learning adds on top of the lift reflex: each condition's policies beside the open-loop gait of the same
trials, per terrain, over the same episodes.

    .venv/bin/python reports/experiments/reflex/against_reflex.py reports/sweeps/reflex [--conditions reflex,default]

In a trial run with `task.lift_reflex=true` the evaluation's `open_loop` controller (cpg.initial: a 0.25, b 0.2 at
its floor, omega 1.5 pi, held) walks with the reflex too, so its column is the reflex alone under a gait no policy
chose. Prints, per terrain, success (mean over trials), and over the episodes that arrive the cost of transport and
time to goal (s), for the policy and for the open-loop gait; then the suite's totals.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

CONTROLLERS = {"policy": "policy", "open_loop": "open loop"}


def trial_rows(sweep: Path, condition: str) -> pd.DataFrame:
    """Every evaluation row of the condition's trials in the sweep's report folder, with a `trial` column."""
    frames = []
    for path in sorted(sweep.glob(f"{condition}-seed*/eval/results.csv")):
        rows = pd.read_csv(path)
        missing = {"controller", "terrain", "success", "cost_of_transport", "time"} - set(rows.columns)
        if missing:
            raise SystemExit(f"error: {path} is not an evaluate results.csv (missing {sorted(missing)})")
        frames.append(rows.assign(trial=path.parent.parent.name))
    if not frames:
        raise SystemExit(f"error: {sweep} holds no trial of condition {condition!r} with eval/results.csv")
    return pd.concat(frames, ignore_index=True)


def per_terrain(rows: pd.DataFrame) -> pd.DataFrame:
    """Per terrain and controller: success (mean over trials of each trial's rate), and the cost of transport and
    time to goal of the episodes that arrived."""
    rows = rows[rows.controller.isin(CONTROLLERS) & (rows.terrain != "varied")]
    success = rows.groupby(["terrain", "controller", "trial"]).success.mean().groupby(["terrain", "controller"]).mean()
    arrived = rows[rows.success].groupby(["terrain", "controller"])[["cost_of_transport", "time"]].mean()
    table = pd.concat([success.rename("success"), arrived], axis=1).unstack("controller")
    table.columns = [f"{CONTROLLERS[c]} {m.replace('cost_of_transport', 'CoT')}" for m, c in table.columns]
    return table[[f"{name} {m}" for name in CONTROLLERS.values() for m in ("success", "CoT", "time")]]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sweep", type=Path, help="a sweep's report folder, e.g. reports/sweeps/reflex")
    ap.add_argument("--conditions", default="reflex", help="comma-separated conditions (default: reflex)")
    a = ap.parse_args()
    for condition in a.conditions.split(","):
        rows = trial_rows(a.sweep, condition)
        table = per_terrain(rows)
        trials = rows.trial.nunique()
        print(f"{condition}: {trials} trials; success is the mean over trials, CoT and time (s) over arrivals")
        with pd.option_context("display.width", 200):
            print(table.round(2).to_string())
        suite = rows[rows.controller.isin(CONTROLLERS) & ~rows.terrain.isin(["varied", "flat"])]
        crossed = suite.groupby("controller").success.agg(["sum", "count"])
        print("suite but flat ground: " + ", ".join(
            f"{CONTROLLERS[c]} {int(crossed.loc[c, 'sum'])} of {int(crossed.loc[c, 'count'])}"
            for c in CONTROLLERS if c in crossed.index) + "\n")


if __name__ == "__main__":
    main()
