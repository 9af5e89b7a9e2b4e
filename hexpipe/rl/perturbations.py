"""Training perturbations: the lift knocked down to its floor at random moments (`ppo.lift_drop_rate`).

Why (issue 10, `face_read`): where the default policy fails extra blocks and the block at 0.6 m, the map reads the
face and the policy holds b at its floor instead of lifting. Those states (a face at the feet, b low) are rare in
its own training episodes, because it usually lifts early. A drop puts it there: like legged_gym's random pushes,
it is a perturbation of the state the policy controls, applied in training only; evaluation and the validation
episodes that choose among candidates never see it.

`drop_chance` is the rule (pure); `LiftDrops` is the gymnasium wrapper that applies it inside each training env.
Its draws come from a generator of its own, seeded from the env's reset seed, so the terrain draws of the env's
`np_random` are the same as without it, and a seeded run is repeatable.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

SALT = 0x11F7  # mixed into the reset seed: the drops' stream differs from every other stream of the env


def drop_chance(rate_hz: float, dt: float) -> float:
    """The chance that a Poisson process of `rate_hz` drops per second fires in a control step of `dt` s."""
    return 1.0 - math.exp(-rate_hz * dt)


class LiftDrops(gym.Wrapper):
    """Before a control step, with `drop_chance(rate_hz, control step)`, sets the CPG's lift b to its floor and its
    rate to 0; the step's `info["lift_drops"]` counts the drops since reset."""

    def __init__(self, env: gym.Env, rate_hz: float):
        super().__init__(env)
        if not rate_hz > 0:
            raise ValueError(f"lift drops: rate_hz must be > 0, got {rate_hz!r} (0 means no wrapper)")
        self.chance = drop_chance(rate_hz, env.unwrapped.control_dt)
        self._rng = np.random.default_rng(SALT)  # until a seeded reset gives it its own stream
        self.drops = 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        if seed is not None:
            self._rng = np.random.default_rng([seed, SALT])
        self.drops = 0
        obs, info = self.env.reset(seed=seed, options=options)
        return obs, {**info, "lift_drops": 0}

    def step(self, action):
        if self._rng.random() < self.chance:
            self.env.unwrapped.cpg.drop_lift()
            self.drops += 1
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, {**info, "lift_drops": self.drops}
