"""The commanded lift b per 0.1 m of the base's distance, one row per evaluation episode of one sweep trial, with
how the episode ended: where on a course the lift sags in the episodes that stall.

    .venv/bin/python reports/experiments/lift_zone/b_by_distance.py zone_swap feet30-seed2 extra_blocks

Reads data/sweeps/SWEEP/TRIAL/eval/cpg_traces.csv.gz and reports/sweeps/SWEEP/episodes.csv (the learned policy only).
"""

import argparse
from pathlib import Path

import numpy as np
import pandas as pd


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sweep")
    parser.add_argument("trial", help="CONDITION-seedN")
    parser.add_argument("terrain")
    parser.add_argument("--start", type=float, default=0.3, help="first bin's lower edge (m)")
    parser.add_argument("--stop", type=float, default=2.6, help="last bin's upper edge (m)")
    args = parser.parse_args()
    traces_path = Path("data/sweeps") / args.sweep / args.trial / "eval" / "cpg_traces.csv.gz"
    episodes_path = Path("reports/sweeps") / args.sweep / "episodes.csv"
    for path in (traces_path, episodes_path):
        if not path.exists():
            raise SystemExit(f"error: {path} not found (run the sweep first)")
    traces = pd.read_csv(traces_path)
    traces = traces[(traces.terrain == args.terrain) & (traces.controller == "policy")]
    if traces.empty:
        raise SystemExit(f"error: no policy traces on {args.terrain} in {traces_path}")
    episodes = pd.read_csv(episodes_path)
    episodes = episodes[(episodes.trial == args.trial) & (episodes.controller == "policy")
                        & (episodes.terrain == args.terrain)].set_index("episode")
    edges = np.round(np.arange(args.start, args.stop + 1e-9, 0.1), 2)
    print(f"{args.trial} on {args.terrain}: mean b (rad) per 0.1 m of the base's distance, bins from {edges[0]} m")
    print("episode | end | " + " ".join(f"{e:4.1f}" for e in edges[:-1]))
    for episode, trace in traces.groupby("episode"):
        bins = pd.cut(trace.distance, edges)
        b = trace.groupby(bins, observed=False).b.mean().to_numpy()
        row = episodes.loc[episode]
        end = "goal" if row.success else f"{row.termination} at {row.distance:.2f} m ({row.stall_legs})"
        print(f"{episode} | {end} | " + " ".join(f"{x:4.2f}" if x == x else "  - " for x in b))


if __name__ == "__main__":
    main()
