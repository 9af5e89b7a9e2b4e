"""Per trial of a sweep, the learned policy's figures that the lift_drops section reads: success on the suite but
flat ground, extra blocks and the block at 0.6 m, the lift before the single block's face minus on its open ground
(rad), and on flat ground its cost of transport, time to goal (s, against the best fixed gait's) and mean gait.

    .venv/bin/python reports/experiments/lift_drops/per_seed.py reports/sweeps/lift_drops
"""

import sys
from pathlib import Path

import pandas as pd


def main() -> None:
    if len(sys.argv) != 2:
        sys.exit("usage: per_seed.py SWEEP_REPORT_FOLDER")
    sweep = Path(sys.argv[1])
    files = sorted(sweep.glob("*-seed*/eval/results.csv"))
    if not files:
        sys.exit(f"{sweep}: no trial has eval/results.csv")
    print("trial              suite-flat extra near   lift  | flat: CoT  time  best   a    b   omega")
    for path in files:
        rows = pd.read_csv(path)
        missing = {"controller", "terrain", "success"} - set(rows.columns)
        terrains = {"flat", "single_block", "extra_blocks", "block_near"} - set(rows.get("terrain", ()))
        if missing or terrains:
            sys.exit(f"{path}: not an evaluate results.csv of the suite (missing {sorted(missing | terrains)})")
        policy = rows[rows.controller == "policy"]
        success = policy.groupby("terrain").success.mean()
        single = policy[policy.terrain == "single_block"]
        flat = rows[(rows.terrain == "flat") & rows.success]
        mine, best = flat[flat.controller == "policy"], flat[flat.controller == "best_fixed"]
        print(f"{path.parts[-3]:<18} {success.drop('flat').mean():>10.2f} {success.extra_blocks:>5.1f} "
              f"{success.block_near:>4.1f} {(single.b_before_block - single.b_open).mean():>+6.2f}  | "
              f"{mine.cost_of_transport.mean():>9.2f} {mine.time.mean():>5.2f} {best.time.mean():>5.2f} "
              f"{mine.a_mean.mean():>4.2f} {mine.b_mean.mean():>4.2f} {mine.omega_mean.mean():>5.2f}")


if __name__ == "__main__":
    main()
