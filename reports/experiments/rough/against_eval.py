"""diagnose.py's episodes against the same seeds of evaluate's policy episodes (reports/eval/results.csv).

    .venv/bin/python reports/experiments/rough/against_eval.py reports/experiments/rough/floor25_*.csv

Each CSV's terrain is taken from its name (diagnose.py's OUT named floor25_TERRAIN.csv, or floor25.csv for rough).
Prints, per terrain: successes in evaluate and here, episodes with the same time to the step, and mean times.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd


def main(csvs: list[Path], results: Path) -> None:
    if missing := [str(p) for p in (results, *csvs) if not p.is_file()]:
        raise SystemExit(f"error: no such file: {', '.join(missing)}")
    evaluated = pd.read_csv(results)
    evaluated = evaluated[evaluated["controller"] == "policy"]
    for csv in csvs:
        terrain = csv.stem.partition("_")[2] or "rough"
        here = pd.read_csv(csv).set_index("seed")
        there = evaluated[evaluated["terrain"] == terrain].set_index("seed").loc[here.index]
        same = int(((here["time"] - there["time"]).abs() < 1e-6).sum())
        print(f"{csv.stem:<22} {terrain:<13} evaluate {int(there['success'].sum())}/{len(there)}, "
              f"here {int(here['success'].sum())}/{len(here)}; same time in {same}; "
              f"mean time {there['time'].mean():.2f} -> {here['time'].mean():.2f} s")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csvs", nargs="+", type=Path)
    ap.add_argument("--results", type=Path, default=Path("reports/eval/results.csv"))
    a = ap.parse_args()
    main(a.csvs, a.results)
