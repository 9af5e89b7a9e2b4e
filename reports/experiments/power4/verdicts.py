"""Evaluate's own verdict per draw: on how many terrains a sweep's policy beats the best fixed gait its trial's grid
picked (success at most 5 points below, time to goal no longer, cost of transport lower: `hexpipe evaluate`'s
rule), read from each trial's `eval/metrics.json`. With two arms, the second minus the first per draw, over the
seeds both hold, with a 95% bootstrap interval over seeds.

    .venv/bin/python reports/experiments/power4/verdicts.py order1:order1 power4:power4

Each arm is SWEEP:CONDITION, the sweep's folder under reports/sweeps.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "select"))
from pipelines import load_records  # select/pipelines.py: a sweep's complete trial records

from hexpipe.sweep import stats

SWEEPS = Path(__file__).resolve().parents[2] / "sweeps"
PREFIX = "verdict/policy/"
SUMMARY_KEYS = {"terrains", "terrains_beaten", "beats_best_fixed_everywhere"}


def arm_verdicts(arm: str) -> pd.DataFrame:
    """One row per trial of SWEEP:CONDITION with an evaluation: seed, terrains beaten and which."""
    sweep, _, condition = arm.partition(":")
    if not condition:
        raise SystemExit(f"error: arm {arm!r}: expected SWEEP:CONDITION")
    folder = SWEEPS / sweep
    if not folder.is_dir():
        raise SystemExit(f"error: arm {arm!r}: no sweep folder {folder}")
    rows = []
    for record in load_records([folder], condition):
        metrics_path = folder / record["trial"] / "eval" / "metrics.json"
        if not metrics_path.is_file():
            raise SystemExit(f"error: arm {arm!r}: {metrics_path} not found (a complete trial's evaluation holds it)")
        metrics = json.loads(metrics_path.read_text())
        beaten = [key[len(PREFIX):] for key, value in metrics.items()
                  if key.startswith(PREFIX) and key[len(PREFIX):] not in SUMMARY_KEYS and value == 1]
        rows.append({"seed": int(record["seed"]), "beaten": int(metrics[f"{PREFIX}terrains_beaten"]),
                     "terrains": " ".join(beaten)})
    if not rows:
        raise SystemExit(f"error: arm {arm!r}: no complete trials of {condition!r} in {folder}")
    return pd.DataFrame(rows).set_index("seed").sort_index()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("arms", nargs="+", help="SWEEP:CONDITION (one or two)")
    args = parser.parse_args()
    if len(args.arms) > 2:
        parser.error("at most two arms")
    tables = {arm: arm_verdicts(arm) for arm in args.arms}
    for arm, table in tables.items():
        est = stats.bootstrap_mean([table["beaten"].to_numpy(float)])
        print(f"{arm}: beats its trial's best fixed gait on {est.value:.2f} of 10 terrains per draw "
              f"[{est.low:.2f}, {est.high:.2f}] over {len(table)} draws")
        print(table.to_string(), "\n")
    if len(tables) == 2:
        first, second = tables.values()
        seeds = first.index.intersection(second.index)
        diff = second.loc[seeds, "beaten"].to_numpy(float) - first.loc[seeds, "beaten"].to_numpy(float)
        est = stats.bootstrap_mean([diff])
        per_seed = {int(seed): int(change) for seed, change in zip(seeds, diff, strict=True)}
        print(f"{args.arms[1]} minus {args.arms[0]}, terrains beaten per draw: {est.value:+.2f} "
              f"[{est.low:+.2f}, {est.high:+.2f}] over {len(seeds)} seeds; per seed {per_seed}")


if __name__ == "__main__":
    main()
