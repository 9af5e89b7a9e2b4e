"""How each controller's suite episodes ended, per sweep: counts of goal / stuck / fall, and every policy `fall`.

    .venv/bin/python reports/experiments/tall_fall/terminations.py reports/sweeps/elev_free reports/sweeps/free80 ...

Reads each trial's eval/results.csv (evaluate's rows) under the sweep folders given.
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


if __name__ == "__main__":
    main()
