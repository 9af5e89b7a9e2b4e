"""Why the policy fails on `rough`: the CPG parameters over each episode, and where progress stopped.

    .venv/bin/python reports/experiments/rough/diagnose.py OUT.csv [--policy data/models/ppo] [--terrain rough]
        [--episodes 20] [--set section.key=value ...]

Runs the policy, deterministic, on evaluate's episodes of one terrain (seeds eval.seed onwards, so the same
episodes as reports/eval/results.csv), with params.yaml and any --set overrides applied at run time only (the
policy is not retrained: `--set "cpg.lower=[0.3,0.2,3.141593]"` asks what the same policy does when its stride
may not shorten below 0.3). One row per episode:
- success, termination, end distance (m) and time (s);
- a, b, omega means over the whole episode and over its last `stuck_window` seconds (where a stuck episode made
  no progress);
- `t_a_low`, `x_a_low`: the first time (s) and distance (m) at which a fell below A_LOW after first rising above
  it (it starts at cpg.initial's 0.25), NaN if never; `frac_a_low`: the fraction of steps below it; for a stuck
  episode, `x_stop` is where the last window began (progress stopped there), so x_a_low < x_stop means the
  stride shortened before the stall, not in answer to it.
- with `--faces`: `b_face1`, `b_face2`, the mean b while the front feet (FRONT_REACH ahead of the base) are in the
  BEFORE_FACE before the first and second block's face (NaN where there is none or the body never got there): on
  `extra_blocks`, whether the policy lifts again for the second block.
"""

from __future__ import annotations

import argparse
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

from hexpipe.atomic import write_text
from hexpipe.config import ConfigError, load_params
from hexpipe.evaluation.controllers import ControllerSpec
from hexpipe.evaluation.episodes import BEFORE_FACE, FRONT_REACH, TRACE_COLUMNS, EpisodeJob, run_episode
from hexpipe.evaluation.suite import load_scenarios
from hexpipe.sim.terrain import TerrainError

A_LOW = 0.3  # rad: successes average a = 0.38, failures 0.29-0.31 (every sweep on this recipe)


def _front_lift(col: dict[str, np.ndarray], face: float) -> float:
    """Mean b (rad) while the front feet are in the BEFORE_FACE before `face` (m from the start); NaN if never."""
    front = col["distance"] + FRONT_REACH
    near = (front >= face - BEFORE_FACE) & (front < face)
    return round(float(col["b"][near].mean()), 3) if near.any() else math.nan


def _one(args: tuple[str, str, int, int, tuple[str, ...], bool]) -> dict:
    policy, terrain, index, seed, overrides, faces = args
    params = load_params("params.yaml", overrides=list(overrides))
    scenario = load_scenarios([terrain])[0]
    result = run_episode(params, EpisodeJob(scenario, ControllerSpec("policy", policy), index, seed))
    trace, row = result.trace, result.row
    col = {k: trace[:, i] for i, k in enumerate(TRACE_COLUMNS)}
    window = col["time"] >= col["time"][-1] - params.task.stuck_window
    risen = np.maximum.accumulate(col["a"] >= A_LOW)  # from the first step at or above A_LOW
    low = np.flatnonzero(risen & (col["a"] < A_LOW))
    out = {
        "seed": seed, "success": row["success"], "termination": row["termination"],
        "distance": round(row["distance"], 3), "time": row["time"],
        **{f"{k}_mean": round(float(col[k].mean()), 3) for k in ("a", "b", "omega")},
        **{f"{k}_last": round(float(col[k][window].mean()), 3) for k in ("a", "b", "omega")},
        "t_a_low": float(col["time"][low[0]]) if low.size else math.nan,
        "x_a_low": round(float(col["distance"][low[0]]), 3) if low.size else math.nan,
        "frac_a_low": round(float(np.mean(col["a"] < A_LOW)), 3),
        "x_stop": round(float(col["distance"][window][0]), 3),
    }
    if faces:
        starts = sorted(lo for lo, _ in result.obstacles)
        for i in (1, 2):
            out[f"b_face{i}"] = _front_lift(col, starts[i - 1]) if len(starts) >= i else math.nan
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--policy", default="data/models/ppo")
    ap.add_argument("--terrain", default="rough")
    ap.add_argument("--episodes", type=int, default=20)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--faces", action="store_true", help="add b_face1, b_face2 (see the module docstring)")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    try:
        params = load_params("params.yaml", overrides=a.overrides)  # a bad key or value: one line, not a traceback
        load_scenarios([a.terrain])
    except (ConfigError, TerrainError) as exc:
        raise SystemExit(f"error: {exc}") from None
    if not (Path(a.policy) / "policy.json").is_file():
        raise SystemExit(f"error: no trained policy at {a.policy} (policy.json missing); pass --policy DIR")
    jobs = [(a.policy, a.terrain, i, params.eval.seed + i, tuple(a.overrides), a.faces) for i in range(a.episodes)]
    with ProcessPoolExecutor(a.workers) as pool:
        frame = pd.DataFrame(list(pool.map(_one, jobs)))
    out = write_text(a.out, frame.to_csv(index=False))  # the project's atomic write: a whole file or none
    with pd.option_context("display.width", 200):
        print(frame.to_string(index=False))
        print(f"\nsuccess {frame.success.mean():.2f} over {len(frame)}; by outcome:")
        columns = ["a_mean", "a_last", "b_mean", "frac_a_low"] + (["b_face1", "b_face2"] if a.faces else [])
        print(frame.groupby("success")[columns].mean().round(3).to_string())
    print(f"wrote {len(frame)} episodes to {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
