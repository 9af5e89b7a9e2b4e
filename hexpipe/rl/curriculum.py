"""A terrain curriculum, legged_gym's rule: each env moves up or down difficulty levels by how far it walked.

`next_level` is the rule (pure). `Curriculum` is a gymnasium wrapper that applies it inside each env, between the
episode that ended and the reset that follows, and passes the level to the env as `reset(options={"difficulty"})`
(the `varied` terrain scales block heights, counts and bumps with it; other terrains ignore it). Living in the env,
it needs no VecEnv plumbing, works the same in subprocesses, and stays seeded: its only random draw (where a
top-level env goes next) comes from the env's own `np_random`. `CurriculumStats` logs the levels as a training curve.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

LEVELS = 10  # difficulty = level / (LEVELS - 1): 0, 0.11, ..., 1


def next_level(level: int, distance: float, goal: float, n_levels: int, rng: np.random.Generator) -> int:
    """The level after an episode that walked `distance` m of a `goal`-m course (legged_gym's rule).

    Promote when the env walked the whole course (legged_gym promotes past half a tile, measured from the tile's
    centre: its edge, so the whole course), demote when it walked less than half of it, otherwise stay. An env that
    completes the top level goes to a random level, so the population keeps covering every difficulty.
    """
    if distance >= goal:
        return level + 1 if level + 1 < n_levels else int(rng.integers(0, n_levels))
    if distance < goal / 2:
        return max(level - 1, 0)
    return level


class Curriculum(gym.Wrapper):
    """Keeps one env's difficulty level; `info["difficulty"]` (in [0, 1]) on every reset and step."""

    def __init__(self, env: gym.Env, goal: float, n_levels: int = LEVELS, level: int = 0):
        super().__init__(env)
        if n_levels < 2 or not 0 <= level < n_levels:
            raise ValueError(f"curriculum: need n_levels >= 2 and 0 <= level < n_levels, got {n_levels}, {level}")
        self.goal, self.n_levels, self.level = goal, n_levels, level
        self._walked: float | None = None  # distance of the episode that just ended, until the next reset

    @property
    def difficulty(self) -> float:
        return self.level / (self.n_levels - 1)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        if self._walked is not None:  # drawn from the generator of the episode that ended: seeded
            self.level = next_level(self.level, self._walked, self.goal, self.n_levels, self.env.unwrapped.np_random)
            self._walked = None
        obs, info = self.env.reset(seed=seed, options={**(options or {}), "difficulty": self.difficulty})
        return obs, {**info, "difficulty": self.difficulty}

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        if terminated or truncated:
            self._walked = float(info["distance"])
        return obs, reward, terminated, truncated, {**info, "difficulty": self.difficulty}


class CurriculumStats(BaseCallback):
    """Logs `curriculum/difficulty`: the mean difficulty of the last `window` finished episodes, per rollout."""

    def __init__(self, live: Any | None = None, window: int = 20):
        super().__init__()
        self.live, self.window = live, window
        self.finished: list[float] = []

    def _on_step(self) -> bool:
        for done, info in zip(self.locals["dones"], self.locals["infos"], strict=True):
            if done and "difficulty" in info:
                self.finished.append(float(info["difficulty"]))
        return True

    def _on_rollout_end(self) -> None:
        if self.live is not None and self.finished:
            self.live.step = self.num_timesteps
            self.live.log_metric("curriculum/difficulty", float(np.mean(self.finished[-self.window :])))
