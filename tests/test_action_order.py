"""`cpg.action_order`: the policy sets the CPG parameters' second derivative (2, the paper's) or their rate (1).
A policy is only run under the order it was trained with."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hexpipe.config import CpgConfig, load_params
from hexpipe.envs.hexapod import HexapodEnv

ROOT = Path(__file__).resolve().parents[1]


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


def test_a_policy_runs_only_under_the_action_order_it_was_trained_with(tmp_path):
    from hexpipe.rl.policy import PolicyError, load_policy
    from hexpipe.rl.train import train_ppo

    tiny = [
        "ppo.total_timesteps=64", "ppo.n_steps=64", "ppo.batch_size=64", "ppo.n_epochs=1", "ppo.n_envs=1",
        "ppo.blind=true", "ppo.train_terrains=[single_block]", "task.time_limit=2.0",
        f"ppo.out_dir={tmp_path / 'ppo'}", f"ppo.report_dir={tmp_path / 'reports'}",
    ]
    first = load_params(ROOT / "params.yaml", [*tiny, "cpg.action_order=1"])
    train_ppo(first, show_progress=False)
    assert load_policy(tmp_path / "ppo", first).config["cpg"]["action_order"] == 1
    assert load_policy(tmp_path / "ppo").params.cpg.action_order == 1  # run with its own settings: the trained order
    paper = load_params(ROOT / "params.yaml", [*tiny, "cpg.action_order=2"])
    with pytest.raises(PolicyError, match=r"trained with cpg\.action_order=1 \(its actions are the rates of a, b, "
                                          r"omega\), params now have 2") as err:
        load_policy(tmp_path / "ppo", paper)
    assert "\n" not in str(err.value)
