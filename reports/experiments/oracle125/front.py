"""Is a gait run under a reflex (heading.py's CSV) beaten outright by a plain fixed gait, and does it beat any?

    .venv/bin/python reports/experiments/oracle125/front.py reports/experiments/oracle125/reflex_full.csv \
        reports/experiments/oracle125/reflex_relief.csv --fixed reports/experiments/relief_power125/fixed_gaits125.csv \
        --fixed reports/experiments/oracle125/fixed_high80.csv

Per arm (one CSV, named by its file's stem) and gait, per terrain: success, mean time to goal (s) and cost of
transport over the episodes that arrive, the fixed gaits that cross as often and are both faster and cheaper
(`head150/dominance.py`'s test), and the fixed gaits this gait crosses as often as and is both faster and cheaper
than. Then, per gait, on how many terrains it is dominated and on how many it dominates the fixed gait of its own
stride at b's ceiling (the high gait a fixed controller needs to cross the blocks).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "head150"))
from dominance import dominated_by, label, outcomes, read_fixed, read_fixed_all  # head150/dominance.py


def high_gait(gait: str, ceiling: float) -> str:
    """The fixed gait of `gait`'s stride and cycle at b = `ceiling`, by label: "0.6/0.2/1.25pi" -> "0.6/0.5/1.25pi"."""
    a, _, omega = gait.split("/")
    return f"{a}/{ceiling:g}/{omega}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("arms", type=Path, nargs="+", help="heading.py CSVs of the gaits under a reflex")
    ap.add_argument("--fixed", type=Path, action="append", required=True,
                    help="heading.py's CSV of plain fixed gaits (repeatable; their episodes are pooled)")
    ap.add_argument("--ceiling", type=float, default=0.5, help="b's ceiling (rad): the high fixed gait's lift")
    a = ap.parse_args()
    fixed = outcomes(read_fixed_all(a.fixed), "controller").rename(index=label, level="controller")
    pd.set_option("display.width", 200)
    for path in a.arms:
        mine = outcomes(read_fixed(path), "controller").rename(index=label, level="controller")
        for gait in mine.index.get_level_values("controller").unique():
            high = high_gait(gait, a.ceiling)
            rows = []
            for terrain in mine.loc[gait].index:
                row = mine.loc[(gait, terrain)]
                others = fixed.xs(terrain, level="terrain")
                beaten = [g for g in others.index if dominated_by(others.loc[g], mine.loc[gait].loc[[terrain]])]
                rows.append({"terrain": terrain, "success": row["success"], "time": row["time"], "cot": row["cot"],
                             "high_time": others.loc[high, "time"] if high in others.index else float("nan"),
                             "high_cot": others.loc[high, "cot"] if high in others.index else float("nan"),
                             "dominated_by": " ".join(dominated_by(row, others)) or "-",
                             "dominates": " ".join(beaten) or "-"})
            table = pd.DataFrame(rows).set_index("terrain")
            print(f"{path.stem}: {gait}  (high = the fixed {high})")
            print(table.round(3).to_string())
            n_dom = int((table["dominated_by"] != "-").sum())
            n_high = sum(high in beaten.split() for beaten in table["dominates"])
            print(f"  dominated on {n_dom} of {len(table)} terrains; faster and cheaper than {high} on {n_high}\n")


if __name__ == "__main__":
    main()
