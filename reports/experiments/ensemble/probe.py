"""Several policies trained under one recipe, walked as one controller that lifts when any of them would: at each
control step the b action is the highest of the members' (each member sees the same observation) and the a and
omega actions are the members' mean. Evaluate's episodes of a few terrains, with success, time and cost of
transport per ensemble and terrain.

Why: under `pinned_stride` each training draw misses the lift at a face in its own window of the gait's phase
(seed 1001 in `stride_reflex`, seeds 1 and 2002 in `long_stride`), and the misses are lifts that come too late or
too low. Draws that fail in different windows may cover each other. A pipeline that keeps the best of three PPO
runs (`ppo.candidates=3`) has already paid for three members.

    .venv/bin/python reports/experiments/ensemble/probe.py \\
        --ensemble "odd:data/sweeps/stride_reflex/pinned_stride-seed1/ppo,...,..." [--ensemble NAME:DIRS ...] \\
        [--terrain single_block --terrain extra_blocks] [--episodes 40] [--set section.key=value ...]

--set gives the settings the policies were trained under. Episode i runs with seed eval.seed + i, so its layout
and start are those of episode i in a sweep trial's results and in near_lift/probe.py's readouts.
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ceiling"))
from episodes import add_episode_options, checked_inputs, evaluate_episode  # the helpers in ../ceiling

import hexpipe.evaluation.episodes as episodes_module
from hexpipe.config import Params
from hexpipe.evaluation.controllers import Controller, ControllerSpec, build
from hexpipe.rl.policy import LoadedPolicy, load_policy

SEPARATOR = ","  # an ensemble travels to the workers as a ControllerSpec whose policy_dir joins its members' folders
_members: dict[str, tuple[LoadedPolicy, ...]] = {}  # per process: each worker loads an ensemble once


@dataclass(frozen=True)
class LiftVote:
    """The members' actions combined: b's the highest (lift if any member lifts), a's and omega's the mean."""

    members: tuple[LoadedPolicy, ...]
    initial_cpg: None = None  # as in training: cpg.initial

    @property
    def sensors(self) -> tuple[str, ...]:
        return self.members[0].sensors

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        actions = np.stack([m.predict(obs) for m in self.members])
        combined = actions.mean(axis=0)
        combined[1] = actions[:, 1].max()
        return combined.astype(np.float32)


def _build(spec: ControllerSpec, params: Params) -> Controller:
    """The evaluation's own `build`, with an ensemble for a policy_dir that names several folders."""
    if spec.policy_dir is None or SEPARATOR not in spec.policy_dir:
        return build(spec, params)
    if spec.policy_dir not in _members:
        _members[spec.policy_dir] = tuple(load_policy(Path(d), params) for d in spec.policy_dir.split(SEPARATOR))
    return LiftVote(_members[spec.policy_dir])


def _use_ensembles() -> None:
    episodes_module.build = _build  # run_episode builds its controller through this name


def _one(job: tuple[str, ControllerSpec, str, int, tuple[str, ...]]) -> dict:
    name, controller, terrain, index, overrides = job
    row = evaluate_episode(controller, terrain, index, overrides)
    return {"ensemble": name, **row, "controller": name}  # evaluate's whole row, so the verdict can be computed


def _ensemble(text: str) -> tuple[str, list[str]]:
    name, _, dirs = text.partition(":")
    members = [d for d in dirs.split(SEPARATOR) if d]
    if not name or len(members) < 2:
        raise SystemExit(f"error: ensemble {text!r} is not NAME:DIR,DIR[,DIR...] (two members or more)")
    return name, members


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--ensemble", dest="ensembles", action="append", required=True, metavar="NAME:DIRS")
    add_episode_options(ap, episodes=40)
    a = ap.parse_args()
    terrains = a.terrains or ["single_block", "extra_blocks"]
    ensembles = [_ensemble(text) for text in a.ensembles]
    checked_inputs(a.overrides, terrains, [d for _, members in ensembles for d in members])
    jobs = [(name, ControllerSpec("policy", SEPARATOR.join(members)), t, i, tuple(a.overrides))
            for name, members in ensembles for t in terrains for i in range(a.episodes)]
    with ProcessPoolExecutor(a.workers, initializer=_use_ensembles) as pool:
        rows = pd.DataFrame(list(pool.map(_one, jobs, chunksize=4)))
    if a.csv:
        rows.to_csv(a.csv, index=False)
    won = rows[rows["success"]]
    table = rows.groupby(["terrain", "ensemble"], sort=False).agg(success=("success", "mean"),
                                                                  b_mean=("b_mean", "mean"))
    table = table.join(won.groupby(["terrain", "ensemble"])[["time", "cost_of_transport"]].mean())
    print(f"{len(ensembles)} ensembles (b: the members' highest action), {a.episodes} episodes each; "
          "time and cost over successes")
    for name, members in ensembles:
        print(f"  {name}: " + " ".join(Path(d).parent.name for d in members))
    print(table.round(3).to_string())


if __name__ == "__main__":
    main()
