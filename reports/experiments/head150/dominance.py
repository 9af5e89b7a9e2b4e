"""Is a sweep's policy beaten outright by a fixed gait? Per draw and terrain, a fixed gait dominates the policy when
it crosses at least as often and is both faster (mean time to goal) and cheaper (mean cost of transport, both over
the episodes that arrive). A policy that never arrives on a terrain is dominated there by any gait that arrives
as often.

    .venv/bin/python reports/experiments/head150/dominance.py reports/sweeps/head150 \
        --fixed reports/experiments/head150/fixed_gaits.csv --arm elev150:0 --arm head150:1

Each `--arm CONDITION:GAIN` pairs a condition's trials (their own evaluation, `result.json`) with the fixed gaits'
episodes at that `sim.heading_gain` in the `--fixed` CSVs (heading.py's, the same episodes: evaluate's seeds;
repeat `--fixed` to pool several). The reflexes are part of the robot, so a policy is held against the gaits
walking with the reflex it trained with.
Prints, per arm, each draw's count of dominated terrains (of the CSV's terrains) and by which gaits, the mean over
draws with a 95% bootstrap interval over seeds, and per terrain how many draws are dominated; with two arms, the
second minus the first over the seeds both have. Several report folders may be given: each arm's condition is
read from all of them, so two sweeps' conditions pair draw by draw (the same seeds):

    .venv/bin/python reports/experiments/head150/dominance.py reports/sweeps/one5 reports/sweeps/pin150 \
        --fixed reports/experiments/one5/fixed_gaits.csv --arm free80e04:1 --arm pin150:1
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "select"))
from pipelines import load_records  # select/pipelines.py: a sweep's complete trial records

from hexpipe.sweep import stats


def outcomes(episodes: pd.DataFrame, key: str) -> pd.DataFrame:
    """Per `key` and terrain: success rate, and mean time (s) and cost of transport over the episodes that arrive
    (inf where none does)."""
    arrived = episodes[episodes["success"]]
    out = episodes.groupby([key, "terrain"])["success"].mean().to_frame("success")
    out["time"] = arrived.groupby([key, "terrain"])["time"].mean()
    out["cot"] = arrived.groupby([key, "terrain"])["cost_of_transport"].mean()
    return out.fillna({"time": math.inf, "cot": math.inf})


def label(gait: str) -> str:
    """A gait's short name: "0.8,0.4,3.141593" -> "0.8/0.4/1.00pi"."""
    try:
        a, b, omega = (float(v) for v in gait.split(","))
    except ValueError:
        return gait
    return f"{a:g}/{b:g}/{omega / math.pi:.2f}pi"


def dominated_by(policy: pd.Series, gaits: pd.DataFrame) -> list[str]:
    """The gaits (rows of one terrain's table) that cross as often as `policy` and are faster and cheaper."""
    beats = ((gaits["success"] >= policy["success"] - 1e-9) & (gaits["time"] < policy["time"])
             & (gaits["cot"] < policy["cot"]))
    return list(gaits.index[beats])


def read_fixed_all(paths: list[Path]) -> pd.DataFrame:
    """Several heading.py CSVs of fixed gaits run on the same episodes and settings, pooled."""
    return pd.concat([read_fixed(p) for p in paths], ignore_index=True)


def read_episodes(path: Path, columns: set[str], made_by: str) -> pd.DataFrame:
    """A CSV of episodes; one line, not a traceback, when it is unreadable or lacks the `columns` a readout uses
    (`made_by` names what writes them)."""
    try:
        table = pd.read_csv(path)
    except (OSError, ValueError) as exc:
        raise SystemExit(f"error: {path}: {exc}") from None
    missing = columns - set(table.columns)
    if missing:
        raise SystemExit(f"error: {path} lacks the columns {sorted(missing)} ({made_by} has them)")
    return table


def read_fixed(path: Path) -> pd.DataFrame:
    """heading.py's CSV of the fixed gaits' episodes."""
    return read_episodes(path, {"controller", "gain", "terrain", "success", "time", "cost_of_transport"},
                         "heading.py's --csv")


def gait_outcomes(fixed: pd.DataFrame, gain: float) -> pd.DataFrame:
    """`outcomes` of the fixed gaits walked at heading gain `gain`, indexed by short gait name and terrain."""
    gaits = fixed[fixed["gain"] == gain]
    if gaits.empty:
        raise SystemExit(f"error: the fixed gaits' CSVs have no episodes at gain {gain:g}")
    return outcomes(gaits, "controller").rename(index=label, level="controller")


def policy_episodes(reports: list[Path], condition: str) -> pd.DataFrame:
    rows = [{**ep, "seed": record["seed"]} for record in load_records(reports, condition)
            for ep in record["episodes"] if ep["controller"] == "policy"]
    if not rows:
        raise SystemExit(f"error: no complete {condition} trials in {', '.join(map(str, reports))}")
    return pd.DataFrame(rows)


def arm_counts(reports: list[Path], condition: str, gain: float, fixed: pd.DataFrame) -> pd.DataFrame:
    """One row per draw (seed): the number of terrains on which some gait dominates it, and the gaits that do."""
    gait_table = gait_outcomes(fixed, gain)
    terrains = sorted(gait_table.index.get_level_values("terrain").unique())
    mine = outcomes(policy_episodes(reports, condition), "seed")
    rows = []
    for seed in sorted(mine.index.get_level_values("seed").unique()):
        hit = {t: dominated_by(mine.loc[(seed, t)], gait_table.xs(t, level="terrain"))
               for t in terrains if (seed, t) in mine.index}
        rows.append({"seed": seed, "dominated": sum(bool(v) for v in hit.values()), "terrains": len(hit),
                     **{t: "+".join(v) for t, v in hit.items()}})
    return pd.DataFrame(rows).set_index("seed")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("reports", type=Path, nargs="+", help="the sweeps' report folders (reports/sweeps/NAME)")
    ap.add_argument("--fixed", type=Path, action="append", required=True,
                    help="heading.py's CSV of fixed gaits (repeatable; their episodes are pooled)")
    ap.add_argument("--arm", dest="arms", action="append", required=True, metavar="CONDITION:GAIN")
    a = ap.parse_args()
    fixed = read_fixed_all(a.fixed)
    counts = {}
    for arm in a.arms:
        condition, _, gain = arm.partition(":")
        try:
            counts[arm] = arm_counts(a.reports, condition, float(gain), fixed)
        except ValueError:
            raise SystemExit(f"error: --arm {arm!r} is not CONDITION:GAIN") from None
    for arm, table in counts.items():
        est = stats.bootstrap_mean([table["dominated"].to_numpy(float)])
        terrains = [c for c in table.columns if c not in ("dominated", "terrains")]
        print(f"{arm}: dominated on {est.value:.2f} of {table['terrains'].max()} terrains per draw "
              f"[{est.low:.2f}, {est.high:.2f}] over {len(table)} draws")
        for seed, row in table.iterrows():
            hits = "; ".join(f"{t}: {row[t].replace('+', ' ')}" for t in terrains if row[t])
            print(f"  seed {seed:>5}: {row['dominated']:>2}  {hits or '-'}")
        print("draws dominated, per terrain: "
              + ", ".join(f"{t} {int((table[t] != '').sum())}" for t in terrains) + "\n")
    if len(counts) == 2:
        (name_a, first), (name_b, second) = counts.items()
        seeds = first.index.intersection(second.index)
        diff = second.loc[seeds, "dominated"].to_numpy(float) - first.loc[seeds, "dominated"].to_numpy(float)
        est = stats.bootstrap_mean([diff])
        print(f"{name_b} minus {name_a}, terrains dominated per draw: {est.value:+.2f} [{est.low:+.2f}, "
              f"{est.high:+.2f}] over {len(seeds)} seeds (changed in {int(np.count_nonzero(diff))})")


if __name__ == "__main__":
    main()
