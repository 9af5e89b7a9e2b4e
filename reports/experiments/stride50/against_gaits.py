"""Terrains beaten per sweep trial against each of several fixed gaits, on the same evaluation episodes.

    .venv/bin/python reports/experiments/stride50/against_gaits.py reports/sweeps/stride50 [more sweeps ...] \
        --gait 0.4,0.4,3.141593 --gait 0.5,0.4,3.141593 [--condition cycle125 ...] [--paired A,B ...] [--workers 2]

A sweep's verdict judges its policies against one gait, the grid's best. This readout asks how the count moves
with the bar: it runs each gait on evaluate's episodes (seeds eval.seed onwards, as many a terrain as the trials
ran), then applies evaluate's own verdict (`hexpipe.evaluation.metrics.verdict`) to every trial's policy episodes
(its result.json) against each gait. Several sweeps pool their trials (their evaluation episodes must be the same);
--paired A,B adds, per gait, condition A's terrains beaten minus B's, seed by seed on the seeds both hold, with a
95% bootstrap interval over seeds. Run it on the machine the sweep ran on: fixed-gait episodes differ across CPU
kinds (README, Reproducibility).
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ceiling"))
from episodes import checked_inputs, evaluate_episode, parse_gait  # ceiling/episodes.py, on the path above

from hexpipe.evaluation.controllers import ControllerSpec
from hexpipe.evaluation.metrics import summarise, verdict
from hexpipe.sweep.stats import bootstrap_mean

RAISED = "cpg.upper=[0.5,0.8,6.283185]"  # the ceiling raised so that any gait of the list can be held


def _episode(job: tuple[tuple[float, float, float], str, int]) -> dict:
    gait, terrain, index = job
    row = evaluate_episode(ControllerSpec("best_fixed", gait=gait), terrain, index, (RAISED,))
    return {**row, "controller": _label(gait), "terrain": terrain}


def _label(gait: tuple[float, float, float]) -> str:
    return f"a={gait[0]:.2f} b={gait[1]:.2f} omega={gait[2]:.2f}"


def _trials(sweeps: list[Path], conditions: list[str]) -> tuple[dict[tuple[str, str], pd.DataFrame], dict]:
    """(condition, trial name) -> its policy episodes, for every finished trial of the named conditions (all when
    none) in the sweeps; and (condition, trial name) -> its training seed."""
    out, seeds = {}, {}
    for record in sorted(r for sweep in sweeps for r in sweep.glob("*/result.json")):
        try:
            result = json.loads(record.read_text())
            episodes, condition, seed = result["episodes"], result["condition"], int(result["seed"])
        except (json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
            raise SystemExit(f"error: {record} is not a sweep trial's record ({exc})") from None
        if conditions and condition not in conditions:
            continue
        key = (condition, record.parent.name)
        if key in out:
            raise SystemExit(f"error: trial {key[1]} of condition {condition} is in more than one sweep; "
                             "name one sweep or one --condition")
        rows = pd.DataFrame([e for e in episodes if e["controller"] == "policy"])
        if len(rows):
            out[key], seeds[key] = rows, seed
    if not out:
        wanted = f" of condition {', '.join(conditions)}" if conditions else ""
        where = ", ".join(str(s) for s in sweeps)
        raise SystemExit(f"error: no finished trial{wanted} in {where} (want */result.json)")
    return out, seeds


def _paired(counts: pd.DataFrame, seeds: dict, pair: str) -> list[str]:
    """Lines: per gait, condition A's terrains beaten minus B's over the seeds both hold, with its interval."""
    a, sep, b = pair.partition(",")
    held = set(counts.index.get_level_values("condition"))
    if not sep or a not in held or b not in held:
        raise SystemExit(f"error: --paired {pair!r}: want A,B, two conditions of {sorted(held)}")
    by_seed = counts.set_axis(pd.MultiIndex.from_tuples([(c, seeds[(c, t)]) for c, t in counts.index]))
    gaps = (by_seed.loc[a] - by_seed.loc[b]).dropna().sort_index()  # rows: the seeds both conditions hold
    if gaps.empty:
        raise SystemExit(f"error: --paired {pair!r}: the two conditions share no seed")
    lines = [f"\n{a} minus {b}, terrains beaten, paired over seeds {', '.join(map(str, gaps.index))}"]
    for gait in counts.columns:
        gap = gaps[gait].to_numpy(float)
        if len(gap) > 1:
            est = bootstrap_mean([gap])
            lines.append(f"  {gait}: {est.value:+.2f} [{est.low:+.2f}, {est.high:+.2f}]")
        else:
            lines.append(f"  {gait}: {gap[0]:+.2f} (one seed: no interval)")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("sweeps", type=Path, nargs="+", metavar="sweep")
    ap.add_argument("--gait", dest="gaits", action="append", required=True, metavar="A,B,OMEGA")
    ap.add_argument("--condition", dest="conditions", action="append", default=[])
    ap.add_argument("--paired", action="append", default=[], metavar="A,B")
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    gaits = [parse_gait(g) for g in a.gaits]
    trials, seeds = _trials(a.sweeps, a.conditions)
    first = next(iter(trials.values()))
    terrains = list(dict.fromkeys(first["terrain"]))
    episodes = int(first.groupby("terrain").size().max())
    checked_inputs((RAISED,), terrains)
    jobs = [(g, t, i) for g in gaits for t in terrains for i in range(episodes)]
    with ProcessPoolExecutor(a.workers) as pool:
        fixed = pd.DataFrame(list(pool.map(_episode, jobs)))
    labels = [_label(g) for g in gaits]
    beaten, per_terrain = {}, {}
    for (condition, trial), rows in trials.items():
        table = summarise(pd.concat([rows, fixed]), terrains, ["policy", *labels])
        for label in labels:
            calls = verdict(table, terrains, baseline=label)
            beaten[(condition, trial, label)] = sum(v.beats for v in calls)
            for v in calls:
                key = (v.terrain, condition, label)
                per_terrain[key] = per_terrain.get(key, 0) + int(v.beats)
    counts = pd.Series(beaten).unstack()[labels].rename_axis(["condition", "trial"])
    with pd.option_context("display.width", 200):
        print(f"fixed gaits on {episodes} episodes a terrain: success, time to goal (s), cost of transport")
        arrived = fixed[fixed["success"]]
        print(pd.concat({"success": fixed.pivot_table(index="terrain", columns="controller", values="success"),
                         "time": arrived.pivot_table(index="terrain", columns="controller", values="time"),
                         "cost": arrived.pivot_table(index="terrain", columns="controller",
                                                     values="cost_of_transport")}, axis=1)
              .reindex(terrains).round(2).to_string())
        print("\nterrains beaten of", len(terrains), "per trial, against each gait")
        print(counts.to_string())
        print("\nmean per condition")
        print(counts.groupby(level="condition").mean().round(2).to_string())
        print("\ntrials that beat each gait, per terrain and condition")
        beats = pd.Series(per_terrain).unstack([1, 2]).reindex(terrains).fillna(0).astype(int)
        print(beats.to_string())
        for pair in a.paired:
            print("\n".join(_paired(counts, seeds, pair)))


if __name__ == "__main__":
    main()
