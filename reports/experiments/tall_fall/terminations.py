"""How episodes ended, per sweep: each controller's evaluation (goal / stuck / fall), every policy `fall`, and the
training episodes of all its trials (each trial's ppo/episodes.jsonl, which logs every episode training ended).

    .venv/bin/python reports/experiments/tall_fall/terminations.py reports/sweeps/elev_free reports/sweeps/free80 ...

Reads each trial's eval/results.csv (evaluate's rows) and ppo/episodes.jsonl under the sweep folders given.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sweeps", nargs="+")
    a = ap.parse_args()
    for sweep in a.sweeps:
        files = sorted(Path(sweep).glob("*/eval/results.csv"))
        if not files:
            raise SystemExit(f"error: no */eval/results.csv under {sweep}")
        rows = pd.concat([pd.read_csv(f).assign(trial=f.parent.parent.name) for f in files])
        print(f"== {sweep} ({len(files)} trials)")
        print(rows.groupby(["controller", "termination"]).size().unstack(fill_value=0).to_string())
        falls = rows[(rows.controller == "policy") & (rows.termination == "fall")]
        for r in falls.itertuples():
            print(f"  fall: {r.trial} {r.terrain} episode {r.episode} at {r.distance:.2f} m after {r.time:.2f} s,"
                  f" b mean {r.b_mean:.2f}, a mean {r.a_mean:.2f}")
        logs = sorted(Path(sweep).glob("*/ppo/episodes.jsonl"))
        ends = pd.concat([pd.read_json(f, lines=True)["termination"] for f in logs]) if logs else pd.Series()
        print(f"  training episodes of {len(logs)} trials: {len(ends)}, "
              + ", ".join(f"{k} {v}" for k, v in ends.value_counts().items()))


if __name__ == "__main__":
    main()
