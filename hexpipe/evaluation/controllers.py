"""The controllers compared on the same seeded episodes, and the fixed-gait grid the `best_fixed` baseline comes from.

- `policy`: the learned PPO policy (eval.policy_dir);
- `blind`: a PPO policy trained without the terrain embedding (eval.blind_policy_dir, optional);
- `best_fixed`: the best constant gait of the grid eval.grid_a x grid_b x grid_omega on the training terrains;
- `reflex_gait`: the fixed gait eval.reflex_gait with the lift reflex moving the legs (optional): adaptation by hand;
- `open_loop`: the CPG left at cpg.initial, i.e. what the policy starts from before it steers anything.

A fixed gait is the env with a zero action: the CPG parameters start at the gait with zero rates, and a zero second
derivative keeps them there. Controllers cross process boundaries as `ControllerSpec`s (small and picklable);
`build` turns one into a controller inside the worker, loading a policy once per process.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from hexpipe.config import ConfigError, Params
from hexpipe.rl.policy import LoadedPolicy, load_policy

Gait = tuple[float, float, float]  # (a, b, omega): rad, rad, rad/s

ORDER = ("policy", "blind", "best_fixed", "reflex_gait", "open_loop")  # report order
GRID = "grid"  # controller name of the grid-search episodes


class Controller(Protocol):
    sensors: tuple[str, ...]  # observation sensors the env must provide
    initial_cpg: Gait | None  # CPG parameters at reset; None: cpg.initial

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray: ...


@dataclass(frozen=True)
class ControllerSpec:
    """What to run: a learned policy (`policy_dir`) or a fixed gait (`gait`, None = cpg.initial); `lift_reflex`:
    the env's lift reflex moves the legs (task.lift_reflex) whatever the params say."""

    name: str
    policy_dir: str | None = None
    expect_blind: bool | None = None
    gait: Gait | None = None
    lift_reflex: bool = False


@dataclass(frozen=True)
class FixedGait:
    """Zero action: the CPG holds its initial (a, b, omega) for the whole episode."""

    initial_cpg: Gait | None
    sensors: tuple[str, ...] = ()

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return np.zeros(3, dtype=np.float32)


@dataclass(frozen=True)
class LearnedPolicy:
    policy: LoadedPolicy
    initial_cpg: Gait | None = None  # as in training

    @property
    def sensors(self) -> tuple[str, ...]:
        return self.policy.sensors

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return self.policy.predict(obs)


_policies: dict[tuple[str, bool | None], LoadedPolicy] = {}  # per process: each worker loads a policy once


def build(spec: ControllerSpec, params: Params) -> Controller:
    if spec.policy_dir is None:
        return FixedGait(spec.gait)
    key = (spec.policy_dir, spec.expect_blind)
    if key not in _policies:
        _policies[key] = load_policy(Path(spec.policy_dir), params, expect_blind=spec.expect_blind)
    return LearnedPolicy(_policies[key])


def learned_controllers(params: Params) -> tuple[list[ControllerSpec], dict[str, str], list[str]]:
    """The learned controllers, each loaded once here so that a bad policy fails before any episode runs.

    Returns the specs, a one-line description per controller and notes for the report.
    """
    cfg = params.eval
    specs, notes = [ControllerSpec("policy", cfg.policy_dir)], []
    if cfg.blind_policy_dir:
        if Path(cfg.blind_policy_dir).is_dir():
            specs.append(ControllerSpec("blind", cfg.blind_policy_dir, expect_blind=True))
        else:
            notes.append(f"eval.blind_policy_dir={cfg.blind_policy_dir} does not exist: no `blind` controller")
    described = {}
    for spec in specs:
        policy = load_policy(Path(spec.policy_dir), params, expect_blind=spec.expect_blind)
        described[spec.name] = f"{policy.name} from {spec.policy_dir}"
        notes += [f"`{spec.name}` was trained with {d} (settings changed since)" for d in policy.drift]
    return specs, described, notes


def grid_gaits(params: Params) -> list[Gait]:
    """Every (a, b, omega) of the grid; ConfigError if a value is not positive or an axis is empty. Values outside
    cpg.lower and cpg.upper are fine: a fixed gait runs with the bounds widened to it (`run_episode`), so a default
    that pins the stride is still compared with longer, shorter and faster gaits."""
    cfg = params.eval
    axes = {"grid_a": cfg.grid_a, "grid_b": cfg.grid_b, "grid_omega": cfg.grid_omega}
    for key, values in axes.items():
        if not values:
            raise ConfigError(f"eval.{key} is empty; the best_fixed baseline needs at least one value")
        bad = [v for v in values if not v > 0]
        if bad:
            raise ConfigError(f"eval.{key}: {bad} must be positive (rad, rad, rad/s)")
    return [(float(a), float(b), float(w)) for a, b, w in itertools.product(*axes.values())]


def gait_label(gait: Gait) -> str:
    a, b, omega = gait
    return f"a={a:.2f} b={b:.2f} omega={omega / math.pi:.2f}pi"
