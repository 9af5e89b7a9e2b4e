"""`cpg.action_order`: the policy sets the CPG parameters' second derivative (2, the paper's) or their rate (1).
(That a policy runs only under the order it was trained with: tests/test_ppo.py.)"""

from __future__ import annotations

import numpy as np
import pytest

from hexpipe.config import CpgConfig
from hexpipe.envs.hexapod import HexapodEnv


def lift_after_one_step(order: int) -> float:
    """b (rad) after one control step of full lift from the initial gait, everything else held."""
    env = HexapodEnv("flat", cpg=CpgConfig(action_order=order))
    obs, _ = env.reset(seed=0)
    before = float(obs["cpg"][1])
    obs, *_ = env.step(np.array([0.0, 1.0, 0.0], dtype=np.float32))
    env.close()
    return float(obs["cpg"][1]) - before


def test_a_first_order_action_moves_b_at_its_rate_limit_from_the_first_step():
    cfg = CpgConfig()
    control_dt = 1 / 20
    assert lift_after_one_step(1) == pytest.approx(cfg.rate_limit[1] * control_dt, rel=1e-6)  # 0.05 rad at once
    # order 2 ramps the rate up substep by substep: b moves accel * dt^2 (n + 1) / 2n, about 0.006 rad, in the step
    n = 120 // 20
    assert lift_after_one_step(2) == pytest.approx(cfg.accel_limit[1] * control_dt**2 * (n + 1) / (2 * n), rel=1e-6)
