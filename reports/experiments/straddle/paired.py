"""A sweep's condition against `stride60_ahead`, draw by draw: the same PPO seeds and encoder, one recipe changed
(by default `straddle_train`, with the second training terrain `pairs_open.yaml`; `--sweep long_ahead --condition
stride60_ahead` for the same recipe at 240k steps; `--base SWEEP:CONDITION` for another baseline, as on a CPU kind
whose draws differ, with SWEEP a comma-separated list where the baseline's seeds span sweeps; `--sweep` takes such
a list too). For each seed trained
under both, the change in extra-blocks success, adaptation (lift b before the face minus on open ground,
single_block), suite success (every terrain but flat ground) and flat cost of transport, at sweep scale (10 episodes
a terrain), with the mean change and its 95% bootstrap interval over seeds. `--flat-time` adds flat ground's time
to goal (s, successes) and the policy's mean omega there (rad/s). `--terrain T` (repeatable) adds each draw's
success on terrain T.

    .venv/bin/python reports/experiments/straddle/paired.py [--sweep S[,S] --condition CONDITION] [--base S[,S]:C] \
        [--flat-time] [--terrain T ...]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "select"))
from pipelines import load_records, outcomes

from hexpipe.sweep import stats, tables

BASE = ("ahead_zero", "stride60_ahead", "ahead_third", "best_five")
COLUMNS = ("extra", "lift", "suite", "flat_cot")
FLAT_COLUMNS = ("flat_time", "flat_omega")


def per_draw(sweeps: tuple[str, ...], condition: str, terrains: tuple[str, ...] = ()) -> pd.DataFrame:
    records = load_records([Path("reports/sweeps") / s for s in sweeps], condition)
    if not records:
        raise SystemExit(f"error: no complete {condition} trials in reports/sweeps/{{{','.join(sweeps)}}}")
    episodes = tables.episodes_frame(records)
    draws = outcomes(episodes).drop_duplicates("pipeline").set_index("pipeline")
    policy = episodes[episodes["controller"] == tables.LEARNED]
    by_seed = policy[(policy["terrain"] == "flat") & policy["success"]].groupby("train_seed")
    unknown = sorted(set(terrains) - set(policy["terrain"]))
    if unknown:
        raise SystemExit(f"error: --terrain {unknown[0]!r}: no {condition} episodes on it "
                         f"(terrains: {sorted(set(policy['terrain']))})")
    success = {t: policy[policy["terrain"] == t].groupby("train_seed")["success"].mean() for t in terrains}
    return draws.assign(flat_time=by_seed["time"].mean(), flat_omega=by_seed["omega_mean"].mean(), **success)


def main(sweep: str, condition: str, base_spec: str | None, flat_time: bool = False,
         terrains: tuple[str, ...] = ()) -> None:
    if base_spec is None:
        base_sweeps, base_condition, base_label = BASE, "stride60_ahead", "stride60_ahead"
    else:
        base_sweep, sep, base_condition = base_spec.partition(":")
        if not sep or not base_sweep or not base_condition:
            raise SystemExit(f"error: --base {base_spec!r} is not SWEEP:CONDITION")
        base_sweeps, base_label = tuple(base_sweep.split(",")), base_spec
    new = per_draw(tuple(sweep.split(",")), condition, terrains)
    base = per_draw(base_sweeps, base_condition, terrains)
    seeds = sorted(set(new.index) & set(base.index))
    columns = (COLUMNS + FLAT_COLUMNS if flat_time else COLUMNS) + terrains
    label = sweep if sweep == condition else f"{sweep}:{condition}"
    both = pd.concat({label: new.loc[seeds, list(columns)],
                      base_label: base.loc[seeds, list(columns)]}, axis=1)
    both.index.name = "seed"
    pd.set_option("display.width", 200)
    print(both.round(3).to_string())
    print(f"\nchange per draw, {label} - {base_label}, over {len(seeds)} seeds (mean [95% bootstrap]):")
    width = max([9, *map(len, terrains)])
    for column in columns:
        diff = (new.loc[seeds, column] - base.loc[seeds, column]).to_numpy(float)
        est = stats.bootstrap_mean([diff])
        print(f"  {column:<{width}} {est.value:+.3f} [{est.low:+.3f}, {est.high:+.3f}]   "
              f"means {new.loc[seeds, column].mean():.3f} vs {base.loc[seeds, column].mean():.3f}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sweep", default="straddle_train",
                    help="the sweep under reports/sweeps to read (SWEEP[,SWEEP...] where the seeds span sweeps)")
    ap.add_argument("--condition", default="straddle_train", help="its condition")
    ap.add_argument("--base", default=None,
                    help="SWEEP[,SWEEP...]:CONDITION to pair with (default: stride60_ahead's sweeps)")
    ap.add_argument("--flat-time", action="store_true", help="also flat ground's time to goal and omega")
    ap.add_argument("--terrain", action="append", default=[], help="also each draw's success on this terrain")
    a = ap.parse_args()
    main(a.sweep, a.condition, a.base, a.flat_time, tuple(a.terrain))
