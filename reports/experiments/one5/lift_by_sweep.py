"""Per draw, how much each sweep's policy lifts before the single block's face, split into its two halves: b in the
0.3 m before the face and b on open ground (rad, means over the draw's single-block episodes, as issue 10's
adaptation target and `hexpipe.sweep.tables.adaptation_per_seed` take them). One recipe run on several CPU kinds
is how this was used: which half moves between kinds.

    .venv/bin/python reports/experiments/one5/lift_by_sweep.py five04:free80e04 fall04:free80e04 one5:free80e04

Each argument is SWEEP:CONDITION, a folder under reports/sweeps and the condition of its trials to read.
Prints each draw's row, then per sweep the mean of each column with a 95% bootstrap interval over draws and how
many draws lift 0.15 or more; with several arms, the pooled share of draws that do (Wilson interval) and the
chance, at that share, that five independent draws all do (what a five-pipeline every-draw floor asks).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "select"))
from pipelines import load_records  # select/pipelines.py: a sweep's complete trial records

from hexpipe.sweep import stats
from hexpipe.sweep.tables import HOME_TERRAIN

FLOOR = 0.15  # issue 10's adaptation target (rad)


def draws(sweep: Path, condition: str) -> pd.DataFrame:
    """One row per complete trial of `condition`: its seed, b before the face, b on open ground and their difference."""
    rows = []
    for record in load_records([sweep], condition):
        home = pd.DataFrame([e for e in record["episodes"]
                             if e["controller"] == "policy" and e["terrain"] == HOME_TERRAIN])
        if home.empty:
            continue
        before = pd.to_numeric(home["b_before_block"], errors="coerce").mean()
        open_ground = pd.to_numeric(home["b_open"], errors="coerce").mean()
        rows.append({"arm": f"{sweep.name}:{condition}", "seed": record["seed"], "b_before": before,
                     "b_open": open_ground, "lift": before - open_ground})
    if not rows:
        raise SystemExit(f"error: {sweep}: no complete {condition!r} trial with {HOME_TERRAIN} episodes")
    return pd.DataFrame(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("arms", nargs="+", metavar="SWEEP:CONDITION")
    ap.add_argument("--sweeps", type=Path, default=Path("reports/sweeps"), help="where the sweep folders are")
    a = ap.parse_args()
    frames = []
    for arm in a.arms:
        name, sep, condition = arm.partition(":")
        if not sep or not name or not condition:
            raise SystemExit(f"error: {arm!r} is not SWEEP:CONDITION")
        if not (a.sweeps / name).is_dir():
            raise SystemExit(f"error: {a.sweeps / name}: no such sweep folder")
        frames.append(draws(a.sweeps / name, condition))
    table = pd.concat(frames, ignore_index=True)
    print(table.round(3).to_string(index=False), "\n")
    for name, mine in table.groupby("arm", sort=False):
        parts = []
        for column in ("b_before", "b_open", "lift"):
            est = stats.bootstrap_mean([mine[column].to_numpy(float)])
            parts.append(f"{column} {est.value:.3f} [{est.low:.3f}, {est.high:.3f}]")
        reach = int((mine["lift"] >= FLOOR).sum())
        print(f"{name}: {len(mine)} draws; " + "; ".join(parts) + f"; {reach} of {len(mine)} lift {FLOOR} or more")
    if len(a.arms) > 1:
        reach, n = int((table["lift"] >= FLOOR).sum()), len(table)
        rate = stats.wilson(reach, n)
        print(f"pooled: {reach} of {n} draws lift {FLOOR} or more, {rate.value:.2f} [{rate.low:.2f}, {rate.high:.2f}] "
              f"(Wilson 95%); five draws of five at that rate: {rate.value ** 5:.2f} [{rate.low ** 5:.2f}, "
              f"{rate.high ** 5:.2f}]")


if __name__ == "__main__":
    main()
