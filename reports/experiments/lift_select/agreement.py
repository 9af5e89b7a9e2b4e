"""lift_select's read 1: does the lift on validation episodes rank a sweep's draws as the single block's lift does?

    .venv/bin/python reports/experiments/lift_select/agreement.py reports/sweeps/fall04 \
        reports/experiments/lift_select/validation.csv --condition free80e04

Per draw: train-ppo's validation return (its selection.json) and the mean return of its episodes in the CSV
(the same when the CSV holds train-ppo's validation episodes); the validation lift (mean b before a block face
minus mean b on open ground over its episodes in the CSV) and the single block's lift in the sweep's evaluation
(the adaptation target's measure), each with its two parts (v_ and sb_ before and open, rad); and the Spearman
rank correlation of the two lifts over the draws.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd
from scipy.stats import spearmanr

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "select"))
from pipelines import load_records, validation_lifts, validation_return  # the helpers in select/

from hexpipe.sweep import tables


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sweep", type=Path)
    ap.add_argument("validation", type=Path)
    ap.add_argument("--condition")
    a = ap.parse_args()
    if not a.validation.is_file():
        raise SystemExit(f"error: {a.validation}: no such file")
    records = load_records([a.sweep], a.condition)
    if not records:
        raise SystemExit(f"error: no complete trials in {a.sweep}")
    validation = pd.read_csv(a.validation)
    absent = sorted({r["data"] for r in records} - set(validation.get("trial", [])))
    if absent:
        raise SystemExit(f"error: {a.validation} has no episodes of {', '.join(absent)}")
    v_lift = validation_lifts(validation)
    v_parts = validation.groupby("trial")[["b_before_block", "b_open"]].mean()
    episodes = tables.episodes_frame(records)
    suite = tables.adaptation_per_seed(episodes).set_index("train_seed")["adaptation"]
    home = episodes[(episodes["controller"] == tables.LEARNED) & (episodes["terrain"] == tables.HOME_TERRAIN)]
    s_parts = home.groupby("train_seed")[["b_before_block", "b_open"]].mean()
    own = pd.Series(dtype=float)  # no CSV returns: each draw's own, from its selection.json
    csv_return = validation.groupby("trial")["env_return"].mean()
    rows = pd.DataFrame([{"seed": r["seed"], "validation_return": validation_return(r, own),
                          "csv_return": csv_return.get(r["data"]),
                          "validation_lift": v_lift.get(r["data"]), "single_block_lift": suite.get(r["seed"]),
                          "v_before": v_parts.loc[r["data"], "b_before_block"],
                          "v_open": v_parts.loc[r["data"], "b_open"],
                          "sb_before": s_parts.loc[r["seed"], "b_before_block"],
                          "sb_open": s_parts.loc[r["seed"], "b_open"]}
                         for r in records]).sort_values("seed")
    print(rows.round(3).to_string(index=False))
    rho = spearmanr(rows["validation_lift"], rows["single_block_lift"])
    print(f"Spearman rank correlation over {len(rows)} draws: {rho.statistic:+.3f} (p {rho.pvalue:.3f})")


if __name__ == "__main__":
    main()
