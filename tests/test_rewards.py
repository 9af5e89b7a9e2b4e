"""Reward terms and the cost of transport: pure functions with units."""

import pytest

from hexpipe.envs.rewards import (
    GRAVITY,
    RELIEF_M,
    cost_of_transport,
    forward_velocity_reward,
    lift_penalty,
    lift_waived,
    power_penalty,
)


def test_forward_velocity_reward_is_scaled_velocity():
    assert forward_velocity_reward(0.015, 0.05, 100.0) == pytest.approx(30.0)  # 0.3 m/s
    assert forward_velocity_reward(-0.005, 0.05, 100.0) == pytest.approx(-10.0)  # walking back is penalised


def test_power_penalty_is_linear_in_watts_and_free_at_zero_cost():
    assert power_penalty(80.0, 0.0) == 0.0
    assert power_penalty(80.0, 0.1) == pytest.approx(-8.0)
    assert power_penalty(160.0, 0.1) == pytest.approx(2 * power_penalty(80.0, 0.1))


def test_cost_of_transport_is_energy_per_weight_and_distance():
    assert cost_of_transport(20.0 * GRAVITY * 3.0, 20.0, 3.0) == pytest.approx(1.0)
    assert cost_of_transport(100.0, 20.0, 0.0) > 0  # no division by zero when the robot never moved


def test_failure_penalty_applies_to_giving_up_only():
    from hexpipe.envs.rewards import failure_penalty

    ends = ("stuck", "fall", "goal", None, "nonfinite")
    assert [failure_penalty(t, 300.0) for t in ends] == [-300.0, -300.0, 0, 0, 0]
    assert failure_penalty("stuck", 0.0) == 0.0  # 0: no penalty, the paper's reward


def test_lift_penalty_is_linear_above_the_floor_and_free_at_or_below_it():
    assert lift_penalty(0.45, 0.2, 4.0) == pytest.approx(-1.0)
    assert lift_penalty(0.2, 0.2, 4.0) == 0.0 and lift_penalty(0.1, 0.2, 4.0) == 0.0
    assert lift_penalty(0.45, 0.2, 0.0) == 0.0


def test_the_lift_is_waived_only_where_the_terrain_rises_or_falls_more_than_a_few_cm():
    assert RELIEF_M == 0.03
    assert lift_waived(0.10) and lift_waived(0.031)
    assert not lift_waived(0.0) and not lift_waived(0.03)


def test_a_ramp_is_nothing_before_its_start_linear_between_and_whole_after_its_end():
    from hexpipe.envs.rewards import ramp

    assert [ramp(s, 100, 300) for s in (0, 100, 150, 300, 1000)] == [0.0, 0.0, 0.25, 1.0, 1.0]


def test_time_penalty_is_the_price_per_second_times_the_step():
    from hexpipe.envs.rewards import time_penalty

    assert time_penalty(0.05, 50.0) == pytest.approx(-2.5)  # 50 per s over a 20 Hz control step
    assert time_penalty(0.10, 50.0) == pytest.approx(2 * time_penalty(0.05, 50.0))
    assert time_penalty(0.05, 0.0) == 0.0  # 0: off, the paper's reward


def test_the_time_price_is_charged_every_step_and_logged_only_when_set():
    import numpy as np

    from hexpipe.config import TaskConfig
    from hexpipe.envs.hexapod import HexapodEnv

    charged = HexapodEnv("flat", task=TaskConfig(sensors=(), time_cost=50.0))
    free = HexapodEnv("flat", task=TaskConfig(sensors=()))
    try:
        charged.reset(seed=0)
        free.reset(seed=0)
        for _ in range(3):
            _, r_charged, _, _, info = charged.step(np.zeros(3))
            _, r_free, _, _, free_info = free.step(np.zeros(3))
            assert info["reward_terms"]["time"] == pytest.approx(-50.0 * charged.control_dt)
            assert r_charged == pytest.approx(r_free - 50.0 * charged.control_dt)  # the same step, one more term
        assert "time" not in free_info["reward_terms"]
    finally:
        charged.close()
        free.close()
