"""Per trial of sweeps that draw their own encoder: the encoder's rise probes beside what its policy did.

    .venv/bin/python reports/experiments/encoder_draw/per_trial.py reports/sweeps/encoder_draw [MORE_SWEEP_DIRS...]

Reads each sweep's trials.csv (encoder, distance_r2, height_r2) and episodes.csv (the policy's episodes) and prints,
per trial: the probes, success over the suite but flat ground, the lift before the block over open ground on
single_block (rad), and the cost of transport on flat ground; then Spearman's rank correlation of each probe with
the suite success and with the lift, over all trials given. A sweep without encoders per trial (no encoder column)
is refused by name.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd
from scipy.stats import spearmanr


def per_trial(sweep: Path) -> pd.DataFrame:
    trials = pd.read_csv(sweep / "trials.csv")
    if "encoder" not in trials:
        raise SystemExit(f"{sweep / 'trials.csv'}: no encoder column (the sweep did not run with --train-encoder)")
    episodes = pd.read_csv(sweep / "episodes.csv")
    policy = episodes[episodes["controller"] == "policy"]
    by_trial = policy.groupby("trial")
    single = policy[policy["terrain"] == "single_block"].groupby("trial")
    flat = policy[(policy["terrain"] == "flat") & policy["success"]].groupby("trial")
    out = trials.set_index("trial")[["encoder", "distance_r2", "height_r2"]].copy()
    out["suite_but_flat"] = by_trial.apply(lambda g: g.loc[g["terrain"] != "flat", "success"].mean())
    out["lift_rad"] = single["b_before_block"].mean() - single["b_open"].mean()
    out["flat_cot"] = flat["cost_of_transport"].mean()
    out.insert(0, "sweep", sweep.name)
    return out


def main(paths: list[str]) -> None:
    table = pd.concat([per_trial(Path(p)) for p in paths])
    print(table.round(3).to_string())
    for probe in ("distance_r2", "height_r2"):
        for outcome in ("suite_but_flat", "lift_rad"):
            rho, p = spearmanr(table[probe], table[outcome], nan_policy="omit")
            print(f"Spearman {probe} vs {outcome}: rho {rho:+.2f} (p {p:.2f}, {table[probe].notna().sum()} trials)")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    main(sys.argv[1:])
