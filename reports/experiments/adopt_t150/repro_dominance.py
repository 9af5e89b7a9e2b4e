"""Is a `make repro` pipeline's policy beaten outright by a fixed gait? The question `head150/dominance.py` asks of
a sweep's draws, asked of one pipeline's evaluation: per terrain, a fixed gait dominates a controller when it
crosses at least as often and is both faster and cheaper (means over the episodes that arrive).

    .venv/bin/python reports/experiments/adopt_t150/repro_dominance.py reports/eval/results.csv \
        --fixed reports/experiments/allgrid/grid_15pi.csv [--fixed ...] [--gain 1] [--episodes 10]

Only evaluate's first `--episodes` episodes of each terrain are read (seeds 1000.., the seeds heading.py's fixed
gaits walked), so both sides walk the same draws of friction and mass. Every controller of the results file but
the grid's (policy, best_fixed, reflex_gait, open_loop, ...) is held against the pooled `--fixed` gaits at `--gain`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "head150"))
from dominance import dominated_by, gait_outcomes, outcomes, read_episodes, read_fixed_all

SHOWN = 6  # gaits named per terrain; the rest are counted


def read_results(path: Path, episodes: int) -> pd.DataFrame:
    """evaluate's results.csv, its first `episodes` episodes per terrain and controller, without the grid's rows."""
    results = read_episodes(path, {"terrain", "controller", "episode", "success", "time", "cost_of_transport"},
                            "evaluate's results.csv")
    return results[(results["controller"] != "grid") & (results["episode"] < episodes)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", type=Path, help="evaluate's results.csv (reports/eval/results.csv)")
    ap.add_argument("--fixed", type=Path, action="append", required=True,
                    help="heading.py's CSV of fixed gaits (repeatable; their episodes are pooled)")
    ap.add_argument("--gain", type=float, default=1.0, help="the fixed gaits' sim.heading_gain to read (default 1)")
    ap.add_argument("--episodes", type=int, default=10, help="episodes per terrain read from results (default 10)")
    a = ap.parse_args()
    gait_table = gait_outcomes(read_fixed_all(a.fixed), a.gain)
    n_gaits = gait_table.index.get_level_values("controller").nunique()
    mine = outcomes(read_results(a.results, a.episodes), "controller")
    terrains = sorted(set(gait_table.index.get_level_values("terrain")) & set(mine.index.get_level_values("terrain")))
    for controller in mine.index.get_level_values("controller").unique():
        hits = {t: dominated_by(mine.loc[(controller, t)], gait_table.xs(t, level="terrain"))
                for t in terrains if (controller, t) in mine.index}
        beaten = [t for t, by in hits.items() if by]
        print(f"{controller}: beaten outright on {len(beaten)} of {len(hits)} terrains by a gait of {n_gaits}")
        for t in terrains:
            row = mine.loc[(controller, t)]
            by = hits.get(t, [])
            by = " ".join(by[:SHOWN]) + (f" and {len(by) - SHOWN} more" if len(by) > SHOWN else "") or "-"
            print(f"  {t:<13} success {row['success']:.2f}  time {row['time']:6.2f} s  cot {row['cot']:.3f}  "
                  f"beaten by: {by}")


if __name__ == "__main__":
    main()
