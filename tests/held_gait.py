"""A gait held by a zero action, walked to the episode's end: the reflex tests' walk. The CPG's (a, b, omega) never
change, so whatever the legs do beyond them is the reflexes'."""

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from hexpipe.config import CpgConfig, TaskConfig
from hexpipe.envs.hexapod import HexapodEnv

Row = Callable[[float, dict[str, Any]], Any]  # (base x in m, the step's info) -> what the test keeps of the step


def walk_held(terrain: str, gait: tuple[float, float, float], task: TaskConfig, row: Row, seed: int = 0,
              cpg: CpgConfig | None = None) -> tuple[dict[str, Any], list[Any]]:
    """The last info and `row` of every step. cpg: the bounds (default: pinned at `gait`); each step's reward is
    checked to be the sum of its terms."""
    env = HexapodEnv(terrain, cpg=cpg or CpgConfig().holding(gait), initial_cpg=gait, task=task)
    env.reset(seed=seed)
    rows = []
    try:
        while True:
            _, reward, terminated, truncated, info = env.step(np.zeros(3))
            assert reward == pytest.approx(sum(info["reward_terms"].values()))
            rows.append(row(float(env.robot.base_state()[0][0]), info))
            if terminated or truncated:
                return info, rows
    finally:
        env.close()
