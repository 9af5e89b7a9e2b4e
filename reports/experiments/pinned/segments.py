"""Where on a terrain a condition's policies lose time to their fixed gait: the mean time (s) to cross each 0.25 m
of forward distance, and the mean lift b and stride a (rad) there, for the policy and `best_fixed`, over the
episodes that reached the goal in every trial of the condition (from each trial's eval/cpg_traces.csv.gz under
data/sweeps).

    .venv/bin/python reports/experiments/pinned/segments.py data/sweeps/pinned pinned wide_block rough

Distance is the base's, so the front feet are about 0.57 m ahead of it and the hind feet as far behind
(reports/experiments/lift_zone/feet.py).
"""

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

STEP = 0.25  # m of forward distance per segment


def segments(trace: pd.DataFrame, goal: float = 3.0) -> list[dict]:
    """One row per segment of one episode's trace: the time (s) to cross it and the mean b and a (rad) on it."""
    d, t, b, a = (trace[k].to_numpy() for k in ("distance", "time", "b", "a"))
    rows = []
    for lo in np.arange(0.0, goal, STEP):
        first, last = int(np.argmax(d >= lo)), int(np.argmax(d >= min(lo + STEP, d.max())))
        rows.append({"from_m": round(lo, 2), "time_s": t[last] - t[first], "b": b[first : last + 1].mean(),
                     "a": a[first : last + 1].mean()})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sweep", type=Path, help="a sweep's data folder, e.g. data/sweeps/pinned")
    ap.add_argument("condition")
    ap.add_argument("terrains", nargs="+")
    args = ap.parse_args()
    paths = sorted(args.sweep.glob(f"{args.condition}-seed*/eval/cpg_traces.csv.gz"))
    if not paths:
        raise SystemExit(f"error: {args.sweep}: no trial of {args.condition!r} has eval/cpg_traces.csv.gz")
    traces = pd.concat(pd.read_csv(p).assign(trial=p.parent.parent.name) for p in paths)
    for terrain in args.terrains:
        chosen = traces[(traces.terrain == terrain) & traces.controller.isin(["policy", "best_fixed"])]
        if chosen.empty:
            raise SystemExit(f"error: no trace of terrain {terrain!r} in {args.sweep}")
        rows = [
            {"controller": controller, **row}
            for (controller, _, _), trace in chosen.groupby(["controller", "trial", "episode"])
            if trace.distance.max() >= 3.0
            for row in segments(trace)
        ]
        table = pd.DataFrame(rows).groupby(["from_m", "controller"]).mean().unstack("controller")
        table[("time_s", "policy - fixed")] = table[("time_s", "policy")] - table[("time_s", "best_fixed")]
        print(f"\n{terrain}: {args.condition} ({len(paths)} trials), episodes that reached 3 m, per {STEP} m")
        print(table.round(2).to_string())
        episodes = Path("reports/sweeps") / args.sweep.name / "episodes.csv"  # the sweep's report of every episode
        if episodes.exists():
            ends = pd.read_csv(episodes)
            won = ends[(ends.condition == args.condition) & (ends.terrain == terrain) & (ends.controller == "policy")
                       & ends.success]
            print(f"policy's successes ({len(won)}): correlation of cost of transport with time to goal "
                  f"{won.cost_of_transport.corr(won.time):.2f} ({episodes})")


if __name__ == "__main__":
    main()
