"""Does the return at the end of training rank the draws that lift? Selection that needs no validation episodes.

    .venv/bin/python reports/experiments/select/training_return.py reports/sweeps/zone_swap:feet30 \
        reports/sweeps/zone_fresh:feet30 [--after 0.75]

For each SWEEP_FOLDER:CONDITION, each trial's mean training-episode return (reports/sweeps/NAME/TRIAL/ppo/
episodes.jsonl) over the episodes that ended after `--after` of the trial's last logged step (0.75: once
ppo.lift_cost_ramp has the whole price on), and its lift price per episode, joined with the trial's suite results
(analyse.py's suite_outcomes); prints the table, Spearman's rho of the return against each outcome, and the best
of 3 by that return over every 3-subset of the trials pooled, against single trials (the gain with a bootstrap
interval over whole trials). The training episodes mix curriculum levels and domain randomisation, so this is a
noisier score than validate.py's.
"""

from __future__ import annotations

import argparse
import itertools
import json
from pathlib import Path

import pandas as pd
from analyse import TARGET_LIFT, best_of_k_gain, suite_outcomes
from scipy.stats import spearmanr


def training_scores(trial_dir: Path, after: float) -> dict[str, float]:
    """Mean return and lift price of the training episodes that ended after `after` of the run's last step."""
    path = trial_dir / "ppo" / "episodes.jsonl"
    if not path.is_file():
        raise SystemExit(f"error: {path}: no training episodes (is this a sweep trial folder?)")
    episodes = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    last = max(e["timesteps"] for e in episodes)
    late = [e for e in episodes if e["timesteps"] >= after * last]
    return {"t_return": sum(e["reward"] for e in late) / len(late),
            "t_lift": sum(e["reward_terms"].get("lift", 0.0) for e in late) / len(late),
            "t_episodes": len(late)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sources", nargs="+", metavar="SWEEP_FOLDER:CONDITION")
    ap.add_argument("--after", type=float, default=0.75)
    a = ap.parse_args()
    rows = []
    for source in a.sources:
        folder, _, condition = source.rpartition(":")
        if not (Path(folder) / "episodes.csv").is_file():
            raise SystemExit(f"error: {folder}/episodes.csv not found (SWEEP_FOLDER:CONDITION)")
        outcomes = suite_outcomes(Path(folder))
        outcomes = outcomes[outcomes["condition"] == condition]
        if outcomes.empty:
            raise SystemExit(f"error: no trials of condition {condition!r} in {folder}")
        for _, row in outcomes.iterrows():
            trial = row["trial"].rsplit("/", 1)[1]
            rows.append({"trial": f"{Path(folder).name}/{trial}", **row.drop("trial").to_dict(),
                         **training_scores(Path(folder) / trial, a.after)})
    table = pd.DataFrame(rows).set_index("trial")
    print(table.round(3).to_string())
    for score in ("t_return", "t_lift"):
        for outcome in ("suite", "extra", "lift", "flat_cot"):
            rho, p = spearmanr(table[score], table[outcome])
            print(f"{score:>9} vs {outcome:<8} rho {rho:+.2f} (p {p:.2f}, {len(table)} trials)")
    picks = pd.DataFrame([table.loc[list(sub)].sort_values("t_return").iloc[-1]
                          for sub in itertools.combinations(table.index, 3)])
    print(f"best of 3 by t_return over {len(picks)} subsets: suite {picks['suite'].mean():.3f} "
          f"(single {table['suite'].mean():.3f}), lift {picks['lift'].mean():+.3f} ({table['lift'].mean():+.3f}), "
          f"lift >= {TARGET_LIFT} in {(picks['lift'] >= TARGET_LIFT).mean():.2f} of picks "
          f"({(table['lift'] >= TARGET_LIFT).mean():.2f} of trials), worst suite {picks['suite'].min():.2f}")
    for outcome in ("lift", "suite"):
        gain, low, high = best_of_k_gain(table["t_return"].to_numpy(), table[outcome].to_numpy(), 3)
        print(f"  best of 3 minus a single trial, {outcome}: {gain:+.3f} [{low:+.3f}, {high:+.3f}] "
              "(95% bootstrap over trials)")


if __name__ == "__main__":
    main()
