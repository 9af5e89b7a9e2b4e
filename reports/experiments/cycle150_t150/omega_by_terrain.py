"""Each draw's mean cycle omega (in units of pi) per terrain, over a sweep's policy episodes: where a policy free to
choose its cycle walks fast and where it slows.

    .venv/bin/python reports/experiments/cycle150_t150/omega_by_terrain.py reports/sweeps/cycle150_t150 \
        --condition cycle150_t150
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "head150"))
from dominance import policy_episodes


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("reports", type=Path, nargs="+", help="the sweeps' report folders (reports/sweeps/NAME)")
    ap.add_argument("--condition", required=True)
    a = ap.parse_args()
    episodes = policy_episodes(a.reports, a.condition)
    table = episodes.groupby(["terrain", "seed"])["omega_mean"].mean().unstack("seed") / math.pi
    table["mean"] = table.mean(axis=1)
    with pd.option_context("display.width", 120):
        print(f"{a.condition}: mean omega per episode (pi), per terrain and draw")
        print(table.round(2))


if __name__ == "__main__":
    main()
