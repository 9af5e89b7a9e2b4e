"""Trial records -> the sweep's tables: every evaluated episode, and per (condition, terrain) statistics.

Pure functions on DataFrames and dicts (no files); the intervals come from hexpipe.sweep.stats. A condition's
seeds are the trials of it that completed; a terrain's "all" row pools the terrains of the suite, each seed with
its results on every terrain (`by_seed`).
Issue 10's targets are judged per condition on the policy's per-seed figures (thresholds in
hexpipe.evaluation.metrics).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from hexpipe.evaluation.metrics import (
    ADAPTATION_TARGET,
    ANYWHERE,
    FLAT_COST_OF_TRANSPORT_TARGET,
    HOME_TERRAIN,
    SUCCESS_MARGIN,
    SUCCESS_TARGET,
    SUCCESS_TERRAINS,
)
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


def by_seed(frames: Sequence[pd.DataFrame], column: str = "success") -> list[np.ndarray]:
    """`column` of each per-seed frame (one per terrain, a row per training seed, as `per_seed` gives), for the
    training seeds that every frame holds, in seed order: entry i of every array is the same seed, as the bootstrap
    over whole seeds needs."""
    common = sorted(set.intersection(*(set(f["train_seed"]) for f in frames))) if frames else []
    return [f.set_index("train_seed").loc[common, column].to_numpy(float) for f in frames]


def _cell(seeds: list[pd.DataFrame], confidence: float, resamples: int, seed: int) -> Cell:
    """Statistics of one condition over one or more terrains (one per-seed frame per terrain = stratum)."""
    successes = sum(int(s["successes"].sum()) for s in seeds)
    episodes = sum(int(s["episodes"].sum()) for s in seeds)
    success = by_seed(seeds)
    out: Cell = {"episodes": episodes, "seeds": len(success[0])}
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
        fx, fy, names = [], [], []
        for terrain in terrains:
            x = seeds[(seeds["condition"] == a) & (seeds["terrain"] == terrain)]
            y = seeds[(seeds["condition"] == b) & (seeds["terrain"] == terrain)]
            if len(x) and len(y):
                fx.append(x)
                fy.append(y)
                names.append(terrain)
        if not names:
            continue
        xs, ys = by_seed(fx), by_seed(fy)
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


# ------------------------------------------------------------------------------------------------------------------
# Issue 10's targets
# ------------------------------------------------------------------------------------------------------------------

LEARNED, BASELINE = "policy", "best_fixed"  # the controllers judged and compared, from the same trials
BLIND = "blind"  # the condition that "perception matters" compares with the first condition


@dataclass(frozen=True)
class Target:
    """One of issue 10's targets, met when the per-seed mean is on the right side of the threshold. A target over
    several terrains (`terrains` empty: every suite terrain) is met when it is met on each of them."""

    key: str  # its name in targets.csv and metrics.json
    label: str  # the report's words, with the unit
    threshold: float
    above: bool  # met when value >= threshold (else <=)
    terrains: tuple[str, ...] = ()

    def met(self, value: float) -> bool:
        """On the point estimate; NaN (cannot be scored: e.g. the policy never reached the goal) misses."""
        if math.isnan(value):
            return False
        return value >= self.threshold - 1e-9 if self.above else value <= self.threshold + 1e-9


def issue10_targets(flat: str) -> tuple[Target, ...]:
    """Issue 10's targets, in the report's order; `flat` is the flat-ground terrain (sweep.flat_terrain)."""
    return (
        *(Target(f"success/{t}", f"success on {t}", SUCCESS_TARGET, True, (t,)) for t in SUCCESS_TERRAINS),
        Target("vs_best_fixed", "success - best fixed gait's, worst suite terrain", -SUCCESS_MARGIN, True),
        Target("flat_cost_of_transport", f"cost of transport on {flat}", FLAT_COST_OF_TRANSPORT_TARGET, False,
               (flat,)),
        Target("flat_time_vs_best_fixed", f"time to goal on {flat} - best fixed gait's (s)", 0.0, False, (flat,)),
        Target("adaptation", f"adaptation on {HOME_TERRAIN}: b before the face - b on open ground (rad)",
               ADAPTATION_TARGET, True, (HOME_TERRAIN,)),
        Target("anywhere", f"any block, anywhere: success on {', '.join(ANYWHERE)} - {HOME_TERRAIN}'s, worst",
               -SUCCESS_MARGIN, True, ANYWHERE),
    )


def adaptation_per_seed(episodes: pd.DataFrame, controller: str = LEARNED) -> pd.DataFrame:
    """Per (condition, train_seed): the mean over HOME_TERRAIN's episodes of b_before_block minus the mean of b_open
    (rad; NaN where either was never seen). No rows when the records predate those columns."""
    columns = ["condition", "train_seed", "adaptation"]
    if episodes.empty or not {"b_before_block", "b_open"} <= set(episodes.columns):
        return pd.DataFrame(columns=columns)
    mine = episodes[(episodes["controller"] == controller) & (episodes["terrain"] == HOME_TERRAIN)]
    b = mine[["b_before_block", "b_open"]].apply(pd.to_numeric, errors="coerce")
    means = b.groupby([mine["condition"], mine["train_seed"]], sort=False).mean()
    return (means["b_before_block"] - means["b_open"]).rename("adaptation").reset_index()[columns]


def _for(frame: pd.DataFrame, condition: str) -> pd.DataFrame:
    return frame[frame["condition"] == condition]


def _target_values(key: str, terrain: str, suite: set[str], baseline: set[str], ours: pd.DataFrame,
                   theirs: pd.DataFrame, lift: pd.DataFrame) -> pd.Series | None:
    """One condition's per-seed figure for target `key` on `terrain` (indexed by train_seed), or None where it was
    not measured: the terrain (or the one compared with) not evaluated, or no b columns in the records."""
    def seeds(frame: pd.DataFrame, where: str, column: str) -> pd.Series:
        return frame[frame["terrain"] == where].set_index("train_seed")[column].astype(float)

    if terrain not in suite:
        return None
    if key in ("vs_best_fixed", "flat_time_vs_best_fixed") and terrain not in baseline:
        return None
    if key == "anywhere" and HOME_TERRAIN not in suite:
        return None
    if key == "vs_best_fixed":
        return seeds(ours, terrain, "success") - seeds(theirs, terrain, "success")
    if key == "flat_cost_of_transport":
        return seeds(ours, terrain, "cost_of_transport")
    if key == "flat_time_vs_best_fixed":
        return seeds(ours, terrain, "time_to_goal") - seeds(theirs, terrain, "time_to_goal")
    if key == "adaptation":
        values = lift.set_index("train_seed")["adaptation"].astype(float)
        return None if values.isna().all() else values
    if key == "anywhere":
        return seeds(ours, terrain, "success") - seeds(ours, HOME_TERRAIN, "success")
    return seeds(ours, terrain, "success")  # success/TERRAIN


def target_parts(
    episodes: pd.DataFrame, conditions: Sequence[str], flat: str, confidence: float = 0.95, resamples: int = 10_000,
    seed: int = 0,
) -> pd.DataFrame:
    """One row per (condition, target, terrain) that was evaluated: the mean over seeds of the policy's per-seed
    figure with its percentile bootstrap interval over seeds (low/high NaN below 2 seeds), and `seeds`, the number
    of seeds it was scored on. Comparisons are per seed, within a trial: policy minus the trial's best fixed gait
    (success, time), or minus the policy's own success on HOME_TERRAIN (anywhere). Time and cost of transport are
    of the episodes that reached the goal; a seed where a side never did is left out (value NaN if every seed)."""
    ours = per_seed(episodes[episodes["controller"] == LEARNED])
    theirs = per_seed(episodes[episodes["controller"] == BASELINE])
    lift = adaptation_per_seed(episodes)
    rows = []
    for condition in conditions:
        mine, base = _for(ours, condition), _for(theirs, condition)
        suite = list(dict.fromkeys(mine["terrain"]))
        for target in issue10_targets(flat):
            for terrain in target.terrains or suite:
                values = _target_values(target.key, terrain, set(suite), set(base["terrain"]), mine, base,
                                        _for(lift, condition))
                if values is None:
                    continue
                values = values.dropna().to_numpy(float)
                estimate = (stats.bootstrap_mean([values], confidence, resamples, seed) if len(values)
                            else stats.Estimate(math.nan))
                rows.append({"condition": condition, "target": target.key, "terrain": terrain,
                             "value": estimate.value, "low": estimate.low, "high": estimate.high,
                             "seeds": len(values)})
    return pd.DataFrame(rows, columns=["condition", "target", "terrain", "value", "low", "high", "seeds"])


def judge_targets(parts: pd.DataFrame, conditions: Sequence[str], flat: str) -> pd.DataFrame:
    """One row per (condition, target) measured: the worst terrain's value and interval (the lowest for an "at
    least" target, the highest for "at most"; an unscored NaN first), met on that point estimate."""
    rows = []
    for condition in conditions:
        for target in issue10_targets(flat):
            mine = parts[(parts["condition"] == condition) & (parts["target"] == target.key)]
            if mine.empty:
                continue
            order = mine["value"].sort_values(ascending=target.above, na_position="first").index
            worst = mine.loc[order[0]]
            rows.append({"condition": condition, "target": target.key, "label": target.label,
                         "threshold": target.threshold, "above": target.above, "terrain": worst["terrain"],
                         "value": worst["value"], "low": worst["low"], "high": worst["high"],
                         "seeds": int(worst["seeds"]), "met": target.met(float(worst["value"]))})
    return pd.DataFrame(rows, columns=["condition", "target", "label", "threshold", "above", "terrain", "value",
                                       "low", "high", "seeds", "met"])


def perception_misses(parts: pd.DataFrame, flat: str, blind: str, reference: str) -> list[dict[str, Any]]:
    """The (target, terrain) parts that `blind` misses where its interval lies wholly on the failing side of
    `reference`'s (the intervals do not overlap; both need one): issue 10's "perception matters"."""
    out = []
    for target in issue10_targets(flat):
        for part in parts[(parts["condition"] == blind) & (parts["target"] == target.key)].itertuples():
            ref = parts[(parts["condition"] == reference) & (parts["target"] == target.key)
                        & (parts["terrain"] == part.terrain)]
            if target.met(part.value) or ref.empty or not np.isfinite([part.low, part.high]).all():
                continue
            ref_low, ref_high = float(ref["low"].iloc[0]), float(ref["high"].iloc[0])
            apart = part.high < ref_low if target.above else part.low > ref_high
            if np.isfinite([ref_low, ref_high]).all() and apart:
                out.append({"target": target.key, "terrain": part.terrain, "value": part.value, "low": part.low,
                            "high": part.high, "reference": float(ref["value"].iloc[0]), "reference_low": ref_low,
                            "reference_high": ref_high})
    return out


def target_numbers(judged: pd.DataFrame, parts: pd.DataFrame, misses: list[dict[str, Any]] | None,
                   blind: str = BLIND) -> dict[str, float | int]:
    """Flat metrics.json keys, numbers only (NaN left out): targets/CONDITION/TARGET (+ _low, _high, _met), the
    per-terrain values of targets over several terrains (targets/CONDITION/TARGET/TERRAIN), met and measured counts
    per condition, and, where a blind condition was compared, targets/BLIND/perception_misses and
    targets/perception_matters (1 when it misses at least one target with intervals apart)."""
    out: dict[str, float | int] = {}
    for row in judged.itertuples():
        base = f"targets/{row.condition}/{row.target}"
        out |= stats.Estimate(row.value, row.low, row.high).as_dict(base)
        out[f"{base}_met"] = int(row.met)
    spread = {t.key for t in issue10_targets("") if len(t.terrains) != 1}  # targets over several terrains
    for row in parts.itertuples():
        if row.target in spread and np.isfinite(row.value):
            out[f"targets/{row.condition}/{row.target}/{row.terrain}"] = float(row.value)
    for condition, mine in judged.groupby("condition", sort=False):
        out[f"targets/{condition}/met"] = int(mine["met"].sum())
        out[f"targets/{condition}/measured"] = len(mine)
    if misses is not None:
        out[f"targets/{blind}/perception_misses"] = len(misses)
        out["targets/perception_matters"] = int(bool(misses))
    return out
