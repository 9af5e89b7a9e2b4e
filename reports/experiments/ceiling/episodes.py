"""What the scripts beside this one share: their inputs checked up front, and one of evaluate's episodes.

A bad --set key, terrain name or policy folder is refused in one line before any episode runs. An episode is
evaluate's own: episode `index` of a terrain runs with seed eval.seed + index, so its outcome is the one in a sweep
trial's results.csv for the same policy.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from typing import Any

from hexpipe.config import ConfigError, Params, load_params
from hexpipe.evaluation.controllers import ControllerSpec
from hexpipe.evaluation.episodes import EpisodeJob, run_episode
from hexpipe.evaluation.suite import load_scenarios
from hexpipe.rl.policy import PolicyError, load_policy
from hexpipe.sim.terrain import TerrainError


def checked_inputs(overrides: Sequence[str], terrains: Sequence[str] = (), policies: Sequence[str] = ()) -> Params:
    """params.yaml with the overrides, after checking the terrains and the policies (each loadable under them)."""
    try:
        params = load_params("params.yaml", overrides=list(overrides))
        load_scenarios(list(terrains))
        for policy in policies:
            load_policy(policy, params)
    except (ConfigError, TerrainError, PolicyError) as exc:
        raise SystemExit(f"error: {exc}") from None
    return params


def add_episode_options(ap: argparse.ArgumentParser, episodes: int) -> None:
    """The options the readout scripts share: --terrain (repeatable), --episodes a terrain, --workers, --set
    (repeatable) and --csv."""
    ap.add_argument("--terrain", dest="terrains", action="append")
    ap.add_argument("--episodes", type=int, default=episodes)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    ap.add_argument("--csv", help="also write every episode's row here")


def parse_gait(text: str) -> tuple[float, float, float]:
    """A gait given on the command line as a,b,omega (rad, rad, rad/s); one line naming the text if it is not."""
    try:
        a, b, omega = (float(v) for v in text.split(","))
    except ValueError:
        raise SystemExit(f"error: gait {text!r} is not a,b,omega (three numbers)") from None
    return a, b, omega


def evaluate_episode(controller: ControllerSpec, terrain: str, index: int, overrides: Sequence[str],
                     on_step: Callable[..., None] | None = None) -> dict[str, Any]:
    """Evaluate's episode `index` of `terrain` for the controller: its results row."""
    params = load_params("params.yaml", overrides=list(overrides))
    job = EpisodeJob(load_scenarios([terrain])[0], controller, index, params.eval.seed + index)
    return run_episode(params, job, on_step=on_step).row


def policy_episode(policy: str, terrain: str, index: int, overrides: Sequence[str]) -> tuple[bool, float]:
    """(success, distance in m) of evaluate's episode `index` of `terrain` for the policy in `policy`."""
    row = evaluate_episode(ControllerSpec("policy", policy), terrain, index, overrides)
    return bool(row["success"]), float(row["distance"])


def print_arms(policies: Sequence[str], arms: Sequence[str], episodes: int, outcomes: Sequence[tuple[bool, float]],
               policy_width: int = 40, arm_width: int = 21) -> None:
    """A table of run-time interventions: a header, then per policy its successes in each arm and the distances (m)
    at which the failures stopped. `outcomes` are (success, distance) per episode, ordered policy, arm, episode."""
    print(f"{'policy':<{policy_width}} " + "  ".join(f"{arm:>{arm_width}}" for arm in arms)
          + "   failures (m), per arm")
    out = iter(outcomes)
    for policy in policies:
        runs = [[next(out) for _ in range(episodes)] for _ in arms]
        counts = "  ".join(f"{sum(ok for ok, _ in r):>{arm_width - 3}}/{episodes:<2}" for r in runs)
        fails = " | ".join(" ".join(f"{d:.2f}" for ok, d in r if not ok) or "-" for r in runs)
        print(f"{policy:<{policy_width}} {counts}   {fails}")
