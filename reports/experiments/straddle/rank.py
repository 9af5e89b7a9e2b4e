"""How each validation set ranks the 20 `stride60_ahead` draws of pipelines 0-3: Spearman's rho of the draw's
validation score (two_blocks success and return; train-ppo's own varied_open return) with its suite record
(extra-blocks success, suite success, adaptation at sweep scale, 10 episodes a terrain).

    .venv/bin/python reports/experiments/straddle/rank.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd
from scipy.stats import spearmanr

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "select"))
from pipelines import load_records, outcomes  # noqa: E402

from hexpipe.sweep import tables  # noqa: E402

SWEEPS = ("ahead_zero", "stride60_ahead", "ahead_third", "best_five")


def main() -> None:
    records = load_records([Path("reports/sweeps") / s for s in SWEEPS], "stride60_ahead")
    suite = outcomes(tables.episodes_frame(records)).set_index("trial")
    two = pd.read_csv(HERE / "two_blocks.csv")
    two["trial"] = two["trial"].str.split("/").str[-1]
    two = two.groupby("trial").agg(two_success=("success", "mean"), two_return=("env_return", "mean"))
    own = pd.Series({Path(r["data"]).name: r["selection"]["candidates"][str(r["seed"])]["return"] for r in records},
                    name="own_return")
    df = suite.join(two, how="inner").join(own)
    print(df[["extra", "suite", "lift", "two_success", "two_return", "own_return"]].round(3)
          .sort_values("extra").to_string())
    print(f"\n{len(df)} draws")
    for score in ("two_success", "two_return", "own_return"):
        for outcome in ("extra", "suite", "lift"):
            r = spearmanr(df[score], df[outcome])
            print(f"spearman {score} vs {outcome}: {r.statistic:+.2f} (p {r.pvalue:.2f})")


if __name__ == "__main__":
    main()
