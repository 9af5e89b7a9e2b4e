"""Score trained policies on a validation set drawn from a training distribution (`varied` by default), not the suite.

    .venv/bin/python reports/experiments/select/validate.py OUT.csv TRIAL_DIR [TRIAL_DIR ...] [--episodes 40] \
        [--terrain varied]

Each TRIAL_DIR is a sweep trial's data folder (data/sweeps/NAME/COND-seedN, holding ppo/). Every policy runs the
same `--episodes` episodes of `--terrain` (default `varied`; a name or a terrain file) at full difficulty, seeds
5000.. (evaluate uses 1000..; training draws its own), deterministic, with params.yaml as the sweep trials ran it
(the default conditions: nothing to override).
Writes one row per episode: trial, seed, success, distance, energy (J), termination, time, b's mean, b before a
block face and on open ground (rad; empty where the episode saw none: `pipelines.py --lift-floor` reads them),
and two returns:
- `return`: the power-price reward as `select` measured it (reward_scale x control_hz per m, -power_cost x
  control_hz per J, -failure_penalty on a stuck or fallen end), with no lift term;
- `env_return`: the sum of the env's own rewards, so the whole training reward of params.yaml's task, the lift
  price (task.lift_cost, waived in task.lift_free_zone) included, as train-ppo charges it once its ramp is done.
`--set section.key=value` overrides params.yaml as the sweep's condition did (e.g. task.lift_cost=10).
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pandas as pd

from hexpipe.config import ConfigError, load_params
from hexpipe.envs.rewards import FAILURES
from hexpipe.evaluation.controllers import ControllerSpec
from hexpipe.evaluation.episodes import EpisodeJob, run_episode
from hexpipe.evaluation.suite import load_scenarios
from hexpipe.sim.terrain import TerrainError

SEED0 = 5000


def _one(args: tuple[str, int, tuple[str, ...], str]) -> dict:
    trial, seed, overrides, terrain = args
    params = load_params("params.yaml", overrides=list(overrides))
    scenario = load_scenarios([terrain])[0]
    job = EpisodeJob(scenario, ControllerSpec("policy", str(Path(trial) / "ppo")), seed - SEED0, seed)
    rewards: list[float] = []
    row = run_episode(params, job, on_step=lambda _env, reward, _info, _ended: rewards.append(reward)).row
    task = params.task
    failed = row["termination"] in FAILURES
    ret = (task.reward_scale / (1.0 / params.sim.control_hz) * row["distance"]
           - task.power_cost * params.sim.control_hz * row["energy_j"] - task.failure_penalty * failed)
    return {"trial": trial, "seed": seed, "success": row["success"], "termination": row["termination"],
            "distance": row["distance"], "time": row["time"], "energy_j": row["energy_j"],
            "b_mean": row["b_mean"], "b_before_block": row["b_before_block"], "b_open": row["b_open"],
            "return": ret, "env_return": sum(rewards)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("trials", nargs="+")
    ap.add_argument("--episodes", type=int, default=40)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--terrain", default="varied", help="a terrain name or file to draw the episodes from")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    try:
        load_params("params.yaml", overrides=a.overrides)  # a bad key or value: one line here, not in every worker
    except ConfigError as exc:
        raise SystemExit(f"error: {exc}") from None
    try:
        load_scenarios([a.terrain])
    except TerrainError as exc:
        raise SystemExit(f"error: --terrain: {exc}") from None
    for trial in a.trials:
        if not (Path(trial) / "ppo").is_dir():
            raise SystemExit(f"error: {trial}: no ppo/ folder (expected a sweep trial's data folder)")
    jobs = [(t, SEED0 + i, tuple(a.overrides), a.terrain) for t in a.trials for i in range(a.episodes)]
    with ProcessPoolExecutor(a.workers) as pool:
        rows = list(pool.map(_one, jobs, chunksize=4))
    out = Path(a.out)
    tmp = out.with_suffix(".tmp")
    pd.DataFrame(rows).to_csv(tmp, index=False)
    tmp.replace(out)
    print(f"wrote {len(rows)} episodes to {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
