"""Per-episode rows -> per (terrain, controller) metrics with their spread, the ranking of the fixed-gait grid, and
the verdict: does a learned controller beat the best fixed gait on every terrain?

Intervals are 95%: Wilson's for a success rate (sound at 0 and 100%, where the normal approximation collapses), a
percentile bootstrap of the mean for time to goal and cost of transport (over the episodes that reach the goal;
fixed resampling seed, so a rerun writes the same numbers).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from hexpipe.envs.rewards import FAILURES

Table = dict[str, dict[str, dict[str, float | int]]]  # terrain -> controller -> metric -> number

CONFIDENCE = 0.95
BOOTSTRAP_RESAMPLES = 2000
SUCCESS_MARGIN = 0.05  # the verdict's "success within 5 points of the best fixed gait"
# Issue 10's targets (also judged across seeds by hexpipe.sweep.tables)
HOME_TERRAIN = "single_block"  # the default layout: adaptation is measured on it, moved blocks compared with it
ADAPTATION_TARGET = 0.15  # rad: issue 10's lift before the face over the lift on open ground, on HOME_TERRAIN
ANYWHERE = ("block_near", "block_far", "wide_block")  # the block moved or made deep, against HOME_TERRAIN
SUCCESS_TARGET = 0.95  # success rate on each of SUCCESS_TERRAINS
SUCCESS_TERRAINS = ("single_block", "extra_blocks", "wide_block", "rough")
FLAT_COST_OF_TRANSPORT_TARGET = 1.3  # at most, on flat ground (and time to goal no longer than the best fixed gait's)


def wilson_interval(successes: int, episodes: int) -> tuple[float, float]:
    """95% Wilson score interval of a success rate."""
    from scipy.stats import binomtest

    ci = binomtest(successes, episodes).proportion_ci(CONFIDENCE, method="wilson")
    return float(ci.low), float(ci.high)


def bootstrap_interval(values: Sequence[float]) -> tuple[float, float]:
    """95% percentile-bootstrap interval of the mean; (v, v) for a single value."""
    from scipy.stats import bootstrap

    data = np.asarray(values, dtype=np.float64)
    if len(data) < 2:
        return float(data[0]), float(data[0])
    ci = bootstrap((data,), np.mean, n_resamples=BOOTSTRAP_RESAMPLES, confidence_level=CONFIDENCE,
                   method="percentile", rng=np.random.default_rng(0)).confidence_interval
    return float(ci.low), float(ci.high)


def _spread(mean_key: str, prefix: str, values: pd.Series) -> dict[str, float]:
    """mean, population std (defined for one episode too) and the bootstrap interval of `values`."""
    lo, hi = bootstrap_interval(values.to_numpy())
    return {mean_key: float(values.mean()), f"{prefix}_std": float(values.std(ddof=0)), f"{prefix}_ci_low": lo,
            f"{prefix}_ci_high": hi}


def _group_metrics(g: pd.DataFrame) -> dict[str, float | int]:
    arrived = g[g["success"]]
    successes = len(arrived)
    low, high = wilson_interval(successes, len(g))
    out: dict[str, float | int] = {
        "success_rate": successes / len(g),
        "success_ci_low": low,
        "success_ci_high": high,
        "successes": successes,
        "distance_mean": float(g["distance"].mean()),
        "distance_std": float(g["distance"].std(ddof=0)),
        "fall_rate": float((g["termination"] == "fall").mean()),
        "stuck_rate": float((g["termination"] == "stuck").mean()),
        "a_mean": float(g["a_mean"].mean()),  # CPG parameters averaged over steps, then episodes (rad, rad, rad/s)
        "b_mean": float(g["b_mean"].mean()),
        "omega_mean": float(g["omega_mean"].mean()),
        "episodes": len(g),
    }
    if successes:  # of the episodes that arrive; left out (not NaN) when none did: metrics.json holds numbers only
        out |= _spread("time_to_goal_mean", "time_to_goal", arrived["time"])
        out |= _spread("cost_of_transport", "cost_of_transport", arrived["cost_of_transport"])
    for key in ("b_before_block", "b_open"):  # lift before blocks and on open ground (rad); absent where never seen
        if g[key].notna().any():
            out[key] = float(g[key].mean())
    if "b_before_block" in out and "b_open" in out:
        out["lift_before_block"] = out["b_before_block"] - out["b_open"]  # > 0: lifts for the block only
    return out


def summarise(rows: pd.DataFrame, terrains: Sequence[str], controllers: Sequence[str]) -> Table:
    """{terrain: {controller: metrics}} in the given orders, for every pair that has episodes."""
    table: Table = {}
    for terrain in terrains:
        for controller in controllers:
            g = rows[(rows["terrain"] == terrain) & (rows["controller"] == controller)]
            if len(g):
                table.setdefault(terrain, {})[controller] = _group_metrics(g)
    return table


def rank_gaits(rows: pd.DataFrame, goal_distance: float) -> pd.DataFrame:
    """One row per gait, best first: highest success rate, then lowest mean cost of transport of the episodes that
    reach the goal; ties (and gaits that never arrive) then by longest mean distance counted up to the goal (so
    overshooting it does not count), then shortest mean time to goal.

    The worker pool returns episodes in the order they finish; the rows are sorted first, so that the means (float
    sums) and the ranking come out bit for bit the same on every run."""
    ranked = []
    rows = rows.sort_values(["gait", *(c for c in ("terrain", "episode", "seed") if c in rows)], kind="stable")
    for gait, g in rows.groupby("gait", sort=False):
        arrived = g[g["success"]]
        ranked.append({
            "gait": gait, "success_rate": float(g["success"].mean()),
            "cost_of_transport": float(arrived["cost_of_transport"].mean()) if len(arrived) else math.nan,
            "distance_mean": float(g["distance"].mean()),
            "time_to_goal_mean": float(arrived["time"].mean()) if len(arrived) else math.nan,
            "fall_rate": float((g["termination"] == "fall").mean()),
            "stuck_rate": float((g["termination"] == "stuck").mean()), "episodes": len(g),
            "_progress": float(g["distance"].clip(upper=goal_distance).mean()),
        })
    df = pd.DataFrame(ranked)
    df["_cot"] = df["cost_of_transport"].fillna(math.inf)
    df["_time"] = df["time_to_goal_mean"].fillna(math.inf)
    df = df.sort_values(["success_rate", "_cot", "_progress", "_time"], ascending=[False, True, False, True],
                        kind="stable")
    return df.drop(columns=["_cot", "_progress", "_time"]).reset_index(drop=True)


# ------------------------------------------------------------------------------------------------------------------
# The verdict
# ------------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TerrainVerdict:
    """One learned controller against the best fixed gait on one terrain. A criterion a controller cannot be
    scored on (it never reaches the goal) fails; one the baseline cannot (it never arrives) passes."""

    terrain: str
    success: bool  # success rate no more than SUCCESS_MARGIN below the baseline's
    time: bool  # mean time to goal no longer than the baseline's
    cost_of_transport: bool  # mean cost of transport lower than the baseline's

    @property
    def beats(self) -> bool:
        return self.success and self.time and self.cost_of_transport


def _not_worse(ours: float | None, theirs: float | None, strict: bool) -> bool:
    if ours is None:
        return False
    if theirs is None:
        return True
    return ours < theirs if strict else ours <= theirs


def verdict(table: Table, terrains: Sequence[str], learned: str = "policy",
            baseline: str = "best_fixed") -> list[TerrainVerdict]:
    """Per terrain where both controllers ran: success within 5 points or better, time to goal no longer, cost of
    transport lower (point estimates; the intervals beside them in the report say how sure each call is)."""
    out = []
    for terrain in terrains:
        row = table.get(terrain, {})
        if learned not in row or baseline not in row:
            continue
        ours, theirs = row[learned], row[baseline]
        out.append(TerrainVerdict(
            terrain,
            success=ours["success_rate"] >= theirs["success_rate"] - SUCCESS_MARGIN - 1e-9,
            time=_not_worse(ours.get("time_to_goal_mean"), theirs.get("time_to_goal_mean"), strict=False),
            cost_of_transport=_not_worse(ours.get("cost_of_transport"), theirs.get("cost_of_transport"), strict=True),
        ))
    return out


def adaptation(table: Table, learned: str = "policy") -> dict[str, float]:
    """Issue 10's adaptation and "any block, anywhere" measures for one learned controller, flat numbers:
    on single_block, b before the face, b on open ground and their difference (target >= ADAPTATION_TARGET);
    success on each moved or deep block minus success on single_block (target: no more than 5 points below)."""
    out: dict[str, float] = {}
    home = table.get(HOME_TERRAIN, {}).get(learned)
    if home is None:
        return out
    if "lift_before_block" in home:
        out |= {"b_before_face": home["b_before_block"], "b_open": home["b_open"],
                "lift_before_face": home["lift_before_block"],
                "lift_target_met": int(home["lift_before_block"] >= ADAPTATION_TARGET)}
    moved = [t for t in ANYWHERE if learned in table.get(t, {})]
    for terrain in moved:
        out[f"{terrain}_minus_single_block"] = table[terrain][learned]["success_rate"] - home["success_rate"]
    if moved:
        out["anywhere_target_met"] = int(all(out[f"{t}_minus_single_block"] >= -SUCCESS_MARGIN - 1e-9 for t in moved))
    return out


def summary_numbers(table: Table, terrains: Sequence[str], learned: Sequence[str]) -> dict[str, float | int]:
    """The verdict and adaptation measures as flat metrics.json keys ("verdict/policy/rough": 1, ...)."""
    out: dict[str, float | int] = {}
    for name in learned:
        calls = verdict(table, terrains, name)
        if calls:
            out[f"verdict/{name}/beats_best_fixed_everywhere"] = int(all(v.beats for v in calls))
            out[f"verdict/{name}/terrains_beaten"] = sum(v.beats for v in calls)
            out[f"verdict/{name}/terrains"] = len(calls)
            out |= {f"verdict/{name}/{v.terrain}": int(v.beats) for v in calls}
        by_hand = verdict(table, terrains, name, baseline="reflex_gait")  # only when eval.reflex_gait ran
        if by_hand:
            out[f"verdict_vs_reflex_gait/{name}/terrains_beaten"] = sum(v.beats for v in by_hand)
            out[f"verdict_vs_reflex_gait/{name}/terrains"] = len(by_hand)
        out |= {f"adaptation/{name}/{k}": v for k, v in adaptation(table, name).items()}
    return out


def stall_counts(rows: pd.DataFrame, order: dict[str, Sequence[str]]) -> list[tuple[tuple[str, ...], int, str]]:
    """The episodes that ended stuck or fallen, by the legs that stood at a block face (results.csv's `stall_legs`).

    One entry per combination of the `order` columns (e.g. terrain, then controller) that had any, in the order
    their values are given: (key, episodes, "hind 3, front 1"). Rows recorded before `stall_legs` existed count
    as "-"."""
    ended = rows[rows["termination"].isin(FAILURES)]
    for column, values in order.items():
        ended = ended[ended[column].isin(values)]
    lines = []
    for key, mine in ended.groupby(list(order), sort=False):
        legs = mine["stall_legs"].fillna("-") if "stall_legs" in mine else pd.Series("-", index=mine.index)
        counts = sorted(legs.value_counts().items(), key=lambda kv: (-kv[1], kv[0]))
        rank = tuple(list(order[c]).index(k) for c, k in zip(order, key, strict=True))
        lines.append((rank, tuple(map(str, key)), len(mine), ", ".join(f"{name} {n}" for name, n in counts)))
    return [line[1:] for line in sorted(lines)]
