"""The policy's lift b along the course, per trial: where a draw lets the lift down past a block, and where not.

    .venv/bin/python reports/experiments/price60/lift_profile.py DATA_DIR:CONDITION [...] [--terrain single_block]

DATA_DIR is a sweep's data folder (data/sweeps/NAME, with CONDITION-seedN/eval/cpg_traces.csv.gz, which evaluate
writes and the sweep does not commit). Per trial: the policy's mean b (rad) over every episode's control steps, in
0.25 m bins of the body's forward distance from the start, and its mean b over flat ground's episodes (the last
column). single_block's face is at 1.0 m and its end at 1.3 m; issue 10's "open ground" there starts at 1.8 m
(hexpipe/evaluation/episodes.py).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "long_gaits"))
from lift_onset import read_traces  # long_gaits/lift_onset.py, on the path above

BIN = 0.25  # m


def profile(trial: pd.DataFrame, terrain: str) -> pd.Series:
    """Mean b per distance bin (m, the bin's start) on `terrain`, and over flat ground ('flat'), of one trial's
    policy steps."""
    course, flat = trial[trial.terrain == terrain], trial[trial.terrain == "flat"]
    if course.empty or flat.empty:
        raise SystemExit(f"error: {trial.trial.iloc[0]}: no policy episodes on {terrain} or flat")
    bins = np.floor(course.distance.clip(0, 2.999) / BIN) * BIN
    along = course.groupby(bins.round(2)).b.mean()
    along.index = [f"{start:.2f}" for start in along.index]
    return pd.concat([along, pd.Series({"flat": flat.b.mean()})])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sources", nargs="+", help="DATA_DIR:CONDITION")
    parser.add_argument("--terrain", default="single_block")
    args = parser.parse_args()
    rows = {}
    for source in args.sources:
        traces = read_traces(source, (args.terrain, "flat"), ["terrain", "controller", "distance", "b"])
        for name, trial in traces.groupby("trial", sort=True):
            rows[name] = profile(trial, args.terrain)
    print(f"mean b (rad) on {args.terrain} by the body's distance from the start (m, bin start), policy episodes")
    print(pd.DataFrame(rows).T.round(2).to_string())


if __name__ == "__main__":
    main()
