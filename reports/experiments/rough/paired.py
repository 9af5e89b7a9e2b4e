"""floor25's pre-registered check: trials trained with a's floor at 0.25 against the same seeds of the recipe without.

    .venv/bin/python reports/experiments/rough/paired.py reports/sweeps/floor25 reports/sweeps/epyc30 \
        [--treated floor25] [--control feet30]

Pairs each seed the treated condition ran with the control condition's trial of the same seed (trials from every
sweep named; the first sweep wins a (condition, seed) run twice), prints each trial's outcomes (`pipelines.py`'s:
suite = success on every terrain but flat, extra blocks, the lift on single_block, flat cost of transport, plus
rough), issue 10's targets over seeds for both, and the rule written in the experiments README before the runs:
adopt only if, over the paired seeds, mean rough success >= the control's, mean suite success no more than 0.02
lower, the mean lift no more than 0.03 lower, and flat cost of transport <= 1.3.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "select"))
from pipelines import load_records, outcomes, print_targets  # the experiment script beside this one

from hexpipe.sweep import tables

SUITE_SLACK, LIFT_SLACK, FLAT_COT_MAX = 0.02, 0.03, 1.3


def main(sweeps: list[Path], treated: str, control: str, flat: str = "flat") -> None:
    records: dict[tuple[str, int], dict] = {}
    for record in load_records(sweeps):
        records.setdefault((record["condition"], record["seed"]), record)
    seeds = sorted(s for c, s in records if c == treated and (control, s) in records)
    if not seeds:
        raise SystemExit(f"error: no seed has both a '{treated}' and a '{control}' trial in {[str(s) for s in sweeps]}")
    chosen = [records[(c, s)] for c in (treated, control) for s in seeds]
    episodes = tables.episodes_frame(chosen)
    outcome = outcomes(episodes)
    policy = episodes[episodes["controller"] == tables.LEARNED]
    rough = policy[policy["terrain"] == "rough"].groupby(["condition", "train_seed"])["success"].mean()
    outcome["rough"] = [rough.get((c, s), np.nan) for c, s in zip(outcome["condition"], outcome["pipeline"],
                                                                     strict=True)]
    print(f"seeds {seeds}: {treated} against {control}")
    print(outcome.rename(columns={"pipeline": "seed"}).round(3).to_string(index=False))

    print_targets(episodes, [treated, control], flat, "seeds", width=8)

    paired = outcome.drop(columns="trial").pivot(index="pipeline", columns="condition")
    print()
    for column in ("rough", "suite", "lift", "extra", "flat_cot"):
        diff = (paired[column][treated] - paired[column][control]).to_numpy(float)
        print(f"{treated} - {control}, {column}: {paired[column][treated].mean():.3f} against "
              f"{paired[column][control].mean():.3f}, paired mean {diff.mean():+.3f} "
              f"(per seed {np.round(diff, 3).tolist()})")
    mean = paired.mean()
    checks = {
        "rough >= control": mean[("rough", treated)] >= mean[("rough", control)],
        f"suite >= control - {SUITE_SLACK}": mean[("suite", treated)] >= mean[("suite", control)] - SUITE_SLACK,
        f"lift >= control - {LIFT_SLACK}": mean[("lift", treated)] >= mean[("lift", control)] - LIFT_SLACK,
        f"flat cost of transport <= {FLAT_COT_MAX}": mean[("flat_cot", treated)] <= FLAT_COT_MAX,
    }
    for name, ok in checks.items():
        print(f"rule: {name}: {'yes' if ok else 'no'}")
    print(f"rule met: {'yes' if all(checks.values()) else 'no'}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sweeps", nargs="+", type=Path)
    ap.add_argument("--treated", default="floor25")
    ap.add_argument("--control", default="feet30")
    a = ap.parse_args()
    main(a.sweeps, a.treated, a.control)
