"""Per-episode rows -> per (terrain, controller) metrics, and the ranking of the fixed-gait grid."""

from __future__ import annotations

import math
from collections.abc import Sequence

import pandas as pd

Table = dict[str, dict[str, dict[str, float | int]]]  # terrain -> controller -> metric -> number


def _group_metrics(g: pd.DataFrame) -> dict[str, float | int]:
    goal = g.loc[g["success"], "time"]
    out: dict[str, float | int] = {
        "success_rate": float(g["success"].mean()),
        "distance_mean": float(g["distance"].mean()),
        "distance_std": float(g["distance"].std(ddof=0)),  # population std: defined for a single episode too
        "fall_rate": float((g["termination"] == "fall").mean()),
        "stuck_rate": float((g["termination"] == "stuck").mean()),
        "a_mean": float(g["a_mean"].mean()),  # CPG parameters averaged over steps, then episodes (rad, rad, rad/s)
        "b_mean": float(g["b_mean"].mean()),
        "omega_mean": float(g["omega_mean"].mean()),
        "episodes": len(g),
    }
    if len(goal):  # left out (not NaN) when nothing reached the goal: metrics.json holds numbers only
        out["time_to_goal_mean"] = float(goal.mean())
        out["cost_of_transport"] = float(g.loc[g["success"], "cost_of_transport"].mean())  # of episodes that arrive
    for key in ("b_near_block", "b_open"):  # lift near blocks and on open ground (rad); absent where never seen
        if g[key].notna().any():
            out[key] = float(g[key].mean())
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
    """One row per gait, best first: highest success rate, then longest mean distance counted up to the goal (so
    overshooting it does not count), then shortest mean time to goal (gaits that never arrive last)."""
    ranked = []
    for gait, g in rows.groupby("gait", sort=False):
        goal = g.loc[g["success"], "time"]
        ranked.append({
            "gait": gait, "success_rate": float(g["success"].mean()), "distance_mean": float(g["distance"].mean()),
            "time_to_goal_mean": float(goal.mean()) if len(goal) else math.nan,
            "fall_rate": float((g["termination"] == "fall").mean()),
            "stuck_rate": float((g["termination"] == "stuck").mean()), "episodes": len(g),
            "_progress": float(g["distance"].clip(upper=goal_distance).mean()),
        })
    df = pd.DataFrame(ranked)
    df["_time"] = df["time_to_goal_mean"].fillna(math.inf)
    df = df.sort_values(["success_rate", "_progress", "_time"], ascending=[False, False, True], kind="stable")
    return df.drop(columns=["_progress", "_time"]).reset_index(drop=True)
