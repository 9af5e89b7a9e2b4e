"""Which gait does a sweep's policy walk on each terrain, and how does it compare with the fixed gaits? The readout
behind `dominance.py`'s counts: per terrain, the policy's mean stride a (rad), lift b (rad) and cycle omega
(rad/s) over its episodes, its time to goal (s) and cost of transport with a 95% bootstrap interval over draws,
and each fixed gait's mean time and cost of transport over the same terrain's episodes (at the policy's
`sim.heading_gain`).

    .venv/bin/python reports/experiments/head150/gait_by_terrain.py reports/sweeps/five04 \
        --fixed reports/experiments/five04/fixed_gaits.csv --arm free80e04:1

Time and cost of transport are over the episodes that arrive, as in `dominance.py`; a draw's value is the mean
of its episodes, and the interval is over draws.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd
from dominance import label, outcomes, policy_episodes, read_fixed

from hexpipe.sweep import stats


def interval(values: pd.Series) -> str:
    """'mean [low, high]' over draws, a 95% bootstrap interval."""
    est = stats.bootstrap_mean([values.to_numpy(float)])
    return f"{est.value:.2f} [{est.low:.2f}, {est.high:.2f}]"


def table(episodes: pd.DataFrame, fixed: pd.DataFrame) -> pd.DataFrame:
    """One row per terrain: the policy's gait, time and cost of transport, and each fixed gait's."""
    per_draw = outcomes(episodes, "seed").replace(math.inf, np.nan)
    gaits = outcomes(fixed, "controller").rename(index=label, level="controller")
    rows = []
    for terrain, mine in per_draw.groupby(level="terrain"):
        walked = episodes[episodes["terrain"] == terrain]
        row = {"terrain": terrain, "success": round(float(walked["success"].mean()), 3),
               "a": round(float(walked["a_mean"].mean()), 2), "b": round(float(walked["b_mean"].mean()), 2),
               "omega/pi": round(float(walked["omega_mean"].mean()) / math.pi, 2),
               "time": interval(mine["time"].dropna()), "cot": interval(mine["cot"].dropna())}
        for gait, theirs in gaits.xs(terrain, level="terrain").iterrows():
            row[f"{gait} time"] = round(float(theirs["time"]), 2)
            row[f"{gait} cot"] = round(float(theirs["cot"]), 2)
        rows.append(row)
    return pd.DataFrame(rows).set_index("terrain")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("report", type=Path, help="the sweep's report folder (reports/sweeps/NAME)")
    ap.add_argument("--fixed", type=Path, required=True, help="heading.py's CSV of the fixed gaits")
    ap.add_argument("--arm", required=True, metavar="CONDITION:GAIN")
    a = ap.parse_args()
    condition, _, gain = a.arm.partition(":")
    try:
        gain_value = float(gain)
    except ValueError:
        raise SystemExit(f"error: --arm {a.arm!r} is not CONDITION:GAIN") from None
    fixed = read_fixed(a.fixed)
    fixed = fixed[fixed["gain"] == gain_value]
    if fixed.empty:
        raise SystemExit(f"error: {a.fixed} has no episodes at gain {gain_value:g}")
    episodes = policy_episodes([a.report], condition)
    pd.set_option("display.width", 250)
    pd.set_option("display.max_columns", 30)
    print(f"{condition}: {episodes['seed'].nunique()} draws, {len(episodes)} episodes; the policy's gait, then "
          f"time (s) and cost of transport, mean over draws [95% bootstrap], then each fixed gait's means\n")
    print(table(episodes, fixed).T.to_string())


if __name__ == "__main__":
    main()
