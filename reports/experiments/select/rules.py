"""Two ways to keep one of three candidates, judged on the suite: the highest validation return (train-ppo's rule)
against success first (`ppo.selection=success`: the highest validation return among the candidates whose
validation success is within TOL of the best one's), the order evaluate uses to pick the best fixed gait.

    .venv/bin/python reports/experiments/select/rules.py reports/sweeps/pipe34 [reports/sweeps/floorpipe ...] \
        [--tolerance 0.04]

For every sweep and condition with three or more trials that carry a `selection.json` (their own 60 validation
episodes on `varied`), it prints each trial's validation scores and suite outcomes, then, over every 3-subset of
those trials, the mean outcome of the pick under each rule, and the pipelines (seeds p, p+1000, p+2000 all present)
under each rule. Outcomes: success over the suite but flat ground, extra blocks, the lift on single_block (b in the
0.3 m before the face minus b on open ground), and the share of picks meeting issue 10's extra-blocks (>= 0.95)
and adaptation (>= 0.15 rad) targets.
"""

from __future__ import annotations

import argparse
import itertools
import json
from pathlib import Path

import pandas as pd

from hexpipe.rl.selection import SEED_STRIDE, choose

CANDIDATES = 3
EXTRA_TARGET, LIFT_TARGET = 0.95, 0.15


def trials(sweep: Path) -> pd.DataFrame:
    """One row per trial with a selection.json: its validation return and success, and its suite outcomes."""
    episodes_csv = sweep / "episodes.csv"
    if not episodes_csv.is_file():
        raise SystemExit(f"error: {episodes_csv} not found (a sweep report folder holds it)")
    episodes = pd.read_csv(episodes_csv)
    policy = episodes[episodes["controller"] == "policy"]
    rows = []
    for trial, g in policy.groupby("trial"):
        selection = sweep / trial / "ppo" / "selection.json"
        if not selection.is_file():
            continue
        own = next(iter(json.loads(selection.read_text())["candidates"].values()))
        single = g[g["terrain"] == "single_block"]
        condition, seed = trial.rsplit("-seed", 1)
        rows.append({
            "sweep": sweep.name, "condition": condition, "seed": int(seed),
            "v_return": float(own["return"]), "v_success": float(own["success"]),
            "suite": g.loc[g["terrain"] != "flat", "success"].mean(),
            "extra": g.loc[g["terrain"] == "extra_blocks", "success"].mean(),
            "lift": single["b_before_block"].mean() - single["b_open"].mean(),
        })
    return pd.DataFrame(rows)


def by_return(group: pd.DataFrame) -> int:
    """train-ppo's rule: the highest validation return (the first of equals)."""
    return choose(group["v_return"].tolist())


def success_first(tolerance: float):
    """`ppo.selection=success`: the highest return among the candidates within `tolerance` of the best success."""
    def rule(group: pd.DataFrame) -> int:
        return choose(group["v_return"].tolist(), group["v_success"].tolist(), tolerance)
    return rule


def summary(picks: pd.DataFrame) -> str:
    return (f"suite {picks['suite'].mean():.3f}  extra {picks['extra'].mean():.3f}  lift {picks['lift'].mean():+.3f}"
            f"  extra>={EXTRA_TARGET} {(picks['extra'] >= EXTRA_TARGET).mean():.2f}"
            f"  lift>={LIFT_TARGET} {(picks['lift'] >= LIFT_TARGET).mean():.2f}")


def main(sweeps: list[Path], tolerance: float) -> None:
    frames = [trials(s) for s in sweeps]
    data = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    if data.empty:
        raise SystemExit("error: no trial with a selection.json in " + ", ".join(map(str, sweeps)))
    pd.set_option("display.width", 200)
    print(data.round(3).to_string(index=False))
    rules = {"return": by_return, f"success within {tolerance}": success_first(tolerance)}
    for (sweep, condition), group in data.groupby(["sweep", "condition"], sort=False):
        group = group.reset_index(drop=True)
        if len(group) < CANDIDATES:
            continue
        subsets = list(itertools.combinations(range(len(group)), CANDIDATES))
        print(f"\n{sweep}:{condition}: {len(group)} trials, {len(subsets)} 3-subsets")
        print(f"  {'single draw':24s} {summary(group)}")
        picked = {}
        for name, rule in rules.items():
            rows = [group.iloc[list(s)].iloc[rule(group.iloc[list(s)])] for s in subsets]
            picked[name] = pd.DataFrame(rows)
            print(f"  {name:24s} {summary(picked[name])}")
        first, second = (picked[n] for n in rules)
        same = float((first["seed"].to_numpy() == second["seed"].to_numpy()).mean())
        diff = second[["suite", "extra", "lift"]].to_numpy() - first[["suite", "extra", "lift"]].to_numpy()
        print(f"  second rule minus the first, over subsets: suite {diff[:, 0].mean():+.3f}  extra "
              f"{diff[:, 1].mean():+.3f}  lift {diff[:, 2].mean():+.3f}  (the same pick in {same:.2f})")
        seeds = set(group["seed"])
        for p in sorted(s for s in seeds if s < SEED_STRIDE):
            members = [p + SEED_STRIDE * i for i in range(CANDIDATES)]
            if not set(members) <= seeds:
                continue
            pipe = group.set_index("seed").loc[members]
            kept = {name: int(members[rule(pipe.reset_index())]) for name, rule in rules.items()}
            print(f"  pipeline {p}: " + ", ".join(
                f"{name} keeps {seed} (suite {pipe.loc[seed, 'suite']:.3f}, extra {pipe.loc[seed, 'extra']:.2f}, "
                f"lift {pipe.loc[seed, 'lift']:+.3f})" for name, seed in kept.items()))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sweeps", nargs="+", type=Path)
    parser.add_argument("--tolerance", type=float, default=0.04,
                        help="validation success within this much of the best counts as tied (0.04: two of 60)")
    args = parser.parse_args()
    main(args.sweeps, args.tolerance)
