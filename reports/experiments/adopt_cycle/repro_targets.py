"""Issue 10's targets and the verdict for whole `make repro` pipelines, each read on its own: all of evaluate's
episodes (20 a terrain), the policy against the best fixed gait its 27-gait grid picked.

    .venv/bin/python reports/experiments/adopt_cycle/repro_targets.py NAME=REPORTS [NAME=REPORTS ...]

REPORTS is a `make repro` reports folder (its ppo/selection.json and eval/results.csv, eval/metrics.json). Per
pipeline: the targets met (hexpipe.sweep.tables, as the sweeps judge them, on one seed: no interval), the terrains
where evaluate's verdict says the policy beats the fixed gait, and suite success (every terrain but flat ground).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "select"))
from pipelines import repro_pipeline

from hexpipe.sweep import tables

EPISODES = 10_000  # every episode evaluate ran


def main(pipelines: dict[str, Path], flat: str = "flat") -> None:
    records = []
    for name, reports in pipelines.items():
        _, _, kept = repro_pipeline(reports, EPISODES)
        records.append({**kept, "condition": name})
    episodes = tables.episodes_frame(records)
    names = list(pipelines)
    judged = tables.judge_targets(tables.target_parts(episodes, names, flat), names, flat)
    print("\nissue 10's targets, one pipeline each (worst terrain):")
    print(judged.pivot(index="target", columns="condition", values="value").round(3).loc[
        judged["target"].unique(), names].to_string())
    policy = episodes[episodes["controller"] == tables.LEARNED]
    print("\nper pipeline:")
    for name, reports in pipelines.items():
        metrics = json.loads((reports / "eval" / "metrics.json").read_text())
        mine = judged[judged["condition"] == name]
        mine_policy = policy[policy["condition"] == name]
        beaten = [t for t in dict.fromkeys(mine_policy["terrain"]) if metrics.get(f"verdict/policy/{t}") == 1]
        suite = mine_policy[mine_policy["terrain"] != flat]["success"]
        print(f"{name}: {int(mine['met'].sum())} of {len(mine)} targets met (missed: "
              f"{', '.join(mine.loc[~mine['met'], 'target']) or 'none'}); beats the fixed gait on "
              f"{metrics['verdict/policy/terrains_beaten']} of {metrics['verdict/policy/terrains']} terrains "
              f"({', '.join(beaten)}); suite success {int(suite.sum())}/{len(suite)} = {suite.mean():.3f}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("pipelines", nargs="+", help="NAME=REPORTS: a name and a make repro reports folder")
    args = ap.parse_args()
    parsed = {}
    for item in args.pipelines:
        name, sep, folder = item.partition("=")
        if not sep or not name or not folder:
            raise SystemExit(f"error: {item!r} is not NAME=REPORTS")
        parsed[name] = Path(folder)
    main(parsed)
