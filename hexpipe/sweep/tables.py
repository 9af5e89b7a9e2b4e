"""Trial records -> the sweep's tables: every evaluated episode, and per (condition, terrain) statistics.

Pure functions on DataFrames and dicts (no files); the intervals come from hexpipe.sweep.stats. A condition's
seeds are the trials of it that completed; a terrain's "all" row pools the terrains of the suite (stratified).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
import pandas as pd

from hexpipe.sweep import stats

ALL = "all"  # the pooled row
Cell = dict[str, float | int]


def episodes_frame(records: Iterable[dict[str, Any]]) -> pd.DataFrame:
    """One row per evaluated episode of every complete trial: condition, train_seed, trial, then evaluate's columns
    (its `seed` renamed episode_seed). Empty frame with those columns if there are none."""
    frames = []
    for record in records:
        df = pd.DataFrame(record.get("episodes", []))
        if df.empty:
            continue
        df = df.rename(columns={"seed": "episode_seed"})
        df.insert(0, "trial", record["trial"])
        df.insert(0, "train_seed", record["seed"])
        df.insert(0, "condition", record["condition"])
        frames.append(df)
    if not frames:
        return pd.DataFrame(columns=["condition", "train_seed", "trial", "terrain", "controller", "success"])
    out = pd.concat(frames, ignore_index=True)
    out["success"] = out["success"].astype(bool)
    return out


def per_seed(episodes: pd.DataFrame) -> pd.DataFrame:
    """Per (condition, terrain, train_seed): success rate, episodes, and the mean time to goal and cost of transport
    of the episodes that reached the goal (NaN where none did)."""
    def one(g: pd.DataFrame) -> pd.Series:
        arrived = g[g["success"]]
        return pd.Series({
            "success": g["success"].mean(), "successes": int(g["success"].sum()), "episodes": len(g),
            "time_to_goal": arrived["time"].mean() if len(arrived) else math.nan,
            "cost_of_transport": arrived["cost_of_transport"].mean()
            if len(arrived) and "cost_of_transport" in g else math.nan,
        })

    keys = ["condition", "terrain", "train_seed"]
    if episodes.empty:
        return pd.DataFrame(columns=[*keys, "success", "successes", "episodes", "time_to_goal", "cost_of_transport"])
    return episodes.groupby(keys, sort=False)[list(episodes.columns.drop(keys))].apply(one).reset_index()


def _cell(seeds: list[pd.DataFrame], confidence: float, resamples: int, seed: int) -> Cell:
    """Statistics of one condition over one or more terrains (one per-seed frame per terrain = stratum)."""
    successes = sum(int(s["successes"].sum()) for s in seeds)
    episodes = sum(int(s["episodes"].sum()) for s in seeds)
    success = [s["success"].to_numpy(float) for s in seeds]
    out: Cell = {"episodes": episodes, "seeds": min(len(s) for s in seeds)}
    out |= stats.wilson(successes, episodes, confidence).as_dict("success_rate")
    out |= stats.bootstrap_mean(success, confidence, resamples, seed).as_dict("success_seed_mean")
    out |= stats.bootstrap_iqm(success, confidence, resamples, seed).as_dict("success_iqm")
    if len(seeds) == 1:  # time and energy are per terrain: not pooled over terrains
        for key in ("time_to_goal", "cost_of_transport"):
            values = seeds[0][key].dropna().to_numpy(float)
            if len(values):
                out |= stats.bootstrap_mean([values], confidence, resamples, seed).as_dict(key)
                out[f"{key}_seeds"] = len(values)
    return out


def summarise(
    seeds: pd.DataFrame, conditions: Sequence[str], terrains: Sequence[str], confidence: float = 0.95,
    resamples: int = 10_000, seed: int = 0,
) -> dict[str, dict[str, Cell]]:
    """{condition: {terrain: cell, ..., "all": cell}} for every condition with results; `seeds` from per_seed."""
    table: dict[str, dict[str, Cell]] = {}
    for condition in conditions:
        mine = seeds[seeds["condition"] == condition]
        strata = [mine[mine["terrain"] == t] for t in terrains if (mine["terrain"] == t).any()]
        if not strata:
            continue
        row = {t: _cell([s], confidence, resamples, seed) for t, s in zip(
            [t for t in terrains if (mine["terrain"] == t).any()], strata, strict=True)}
        if len(strata) > 1:
            row[ALL] = _cell(strata, confidence, resamples, seed)
        table[condition] = row
    return table


def default_pairs(conditions: Sequence[str], compare: Sequence[tuple[str, str]]) -> list[tuple[str, str]]:
    """The (a, b) pairs to compare: those asked for, else every condition against the first."""
    return list(compare) if compare else [(c, conditions[0]) for c in conditions[1:]]


def improvements(
    seeds: pd.DataFrame, pairs: Sequence[tuple[str, str]], terrains: Sequence[str], confidence: float = 0.95,
    resamples: int = 10_000, seed: int = 0,
) -> dict[str, dict[str, Cell]]:
    """{"a_vs_b": {terrain: {probability, low, high}, "all": ...}}: P(a's per-seed success > b's)."""
    out: dict[str, dict[str, Cell]] = {}
    for a, b in pairs:
        xs, ys, names = [], [], []
        for terrain in terrains:
            x = seeds[(seeds["condition"] == a) & (seeds["terrain"] == terrain)]["success"].to_numpy(float)
            y = seeds[(seeds["condition"] == b) & (seeds["terrain"] == terrain)]["success"].to_numpy(float)
            if len(x) and len(y):
                xs.append(x)
                ys.append(y)
                names.append(terrain)
        if not names:
            continue
        row = {t: stats.bootstrap_improvement([x], [y], confidence, resamples, seed).as_dict("probability")
               for t, x, y in zip(names, xs, ys, strict=True)}
        if len(names) > 1:
            row[ALL] = stats.bootstrap_improvement(xs, ys, confidence, resamples, seed).as_dict("probability")
        out[f"{a}_vs_{b}"] = row
    return out


def pareto_front(points: dict[str, tuple[float, float]]) -> list[str]:
    """Names of the points (success, cost) that no other point beats on both: higher success, lower cost."""
    finite = {name: p for name, p in points.items() if np.all(np.isfinite(p))}
    return [name for name, p in finite.items()
            if not any(q[0] >= p[0] and q[1] <= p[1] and q != p for q in finite.values())]
