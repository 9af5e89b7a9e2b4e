"""Does a policy's crossing depend on the gait's phase when it meets a face? Evaluate's episodes of one fixed-layout
terrain, more of them than the suite's 10: on a fixed layout with physics not randomised, an episode's seed sets only
the CPG's starting phase. Prints each episode's starting phase of leg 0 (rad), success and distance, then success by
phase bin.

    .venv/bin/python reports/experiments/stride_reflex/phase.py POLICY_DIR [--terrain single_block]
        [--episodes 40] [--set section.key=value ...]

The --set overrides must give the settings the policy was trained under (e.g. `pinned_stride`'s).
"""

from __future__ import annotations

import argparse
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ceiling"))
from episodes import checked_inputs  # the helper in ../ceiling

from hexpipe.config import load_params
from hexpipe.evaluation.controllers import ControllerSpec
from hexpipe.evaluation.episodes import EpisodeJob, run_episode
from hexpipe.evaluation.suite import load_scenarios

SEED0 = 1000  # evaluate's first episode seed (eval.seed), so episodes 0-9 are the suite's own
BINS = 4  # phase bins over the cycle


def _one(job: tuple[str, str, int, tuple[str, ...]]) -> dict:
    policy, terrain, index, overrides = job
    params = load_params("params.yaml", overrides=list(overrides))
    phase: list[float] = []

    def first_phase(env, _reward, _info, _ended) -> None:
        if not phase:
            phase.append(float(np.angle(env.cpg.w[0])) % (2 * math.pi))

    episode = EpisodeJob(load_scenarios([terrain])[0], ControllerSpec("policy", policy), index, SEED0 + index)
    row = run_episode(params, episode, on_step=first_phase).row
    return {"episode": index, "phase": phase[0], "success": row["success"], "distance": row["distance"]}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("policy")
    ap.add_argument("--terrain", default="single_block")
    ap.add_argument("--episodes", type=int, default=40)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    checked_inputs(a.overrides, [a.terrain], [a.policy])  # a bad key, terrain or policy: one line, not a traceback
    jobs = [(a.policy, a.terrain, i, tuple(a.overrides)) for i in range(a.episodes)]
    with ProcessPoolExecutor(a.workers) as pool:
        rows = pd.DataFrame(list(pool.map(_one, jobs)))
    print(f"{a.policy} on {a.terrain}, {a.episodes} episodes (seeds {SEED0}..)")
    print(rows.round(2).sort_values("phase").to_string(index=False))
    rows["bin"] = pd.cut(rows["phase"], np.linspace(0.0, 2 * math.pi, BINS + 1), include_lowest=True)
    print(rows.groupby("bin", observed=False)["success"].agg(["mean", "count"]).round(2).to_string())
    print(f"success {rows['success'].mean():.2f} of {len(rows)}")


if __name__ == "__main__":
    main()
