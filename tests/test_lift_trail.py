"""Follow-the-leader lift (cpg.lift_follows): the lift floors per leg, and the premise that they carry the hind legs
over a block the policy lifted for only at its front legs."""

import math

import numpy as np
import pytest

from hexpipe.config import CpgConfig, TaskConfig
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.sim.cpg import CPG
from hexpipe.sim.lift_trail import WINDOW, LiftTrail, foot_lags, held_lift
from hexpipe.sim.robot import RobotSpec

LAGS = foot_lags(RobotSpec(), 0.3)
LOW_GAIT = (0.25, 0.15, 1.5 * math.pi)


def test_feet_trail_the_front_feet_by_their_spacing():
    assert LAGS[:2] == pytest.approx([0.0, 0.0])
    assert LAGS[2:4] == pytest.approx([0.465, 0.465], abs=0.01)  # middle feet
    assert LAGS[4:] == pytest.approx([0.931, 0.931], abs=0.01)  # hind feet


def test_each_leg_takes_the_lift_commanded_where_the_front_feet_stood_over_it():
    x = np.linspace(0.0, 2.0, 201)
    b = np.where((x >= 0.9) & (x <= 1.1), 0.5, 0.2)  # lifted while the base was at 0.9-1.1 m
    middle_over = held_lift(x, b, 1.0 + LAGS[2], LAGS)
    assert middle_over[2:4] == pytest.approx([0.5, 0.5]) and middle_over[4:] == pytest.approx([0.2, 0.2])
    hind_over = held_lift(x, b, 1.0 + LAGS[4], LAGS)
    assert hind_over[4:] == pytest.approx([0.5, 0.5])
    past = held_lift(x, b, 1.1 + LAGS[4] + WINDOW + 0.05, LAGS)
    assert past[2:] == pytest.approx([0.2] * 4)
    assert np.all(middle_over[:2] == 0) and np.all(hind_over[:2] == 0)  # the front legs follow the command alone


def test_no_floor_before_the_trail_reaches_a_leg():
    assert np.all(held_lift(np.empty(0), np.empty(0), 0.0, LAGS) == 0)
    assert np.all(held_lift(np.array([0.0, 0.05]), np.array([0.5, 0.5]), 0.1, LAGS) == 0)  # 0.1 m walked


def test_trail_drops_its_oldest_sample_when_full():
    trail = LiftTrail(LAGS, capacity=3)
    for i, b in enumerate([0.5, 0.1, 0.1, 0.1]):
        trail.record(float(i), b)
    assert np.all(trail.floor(0.0 + LAGS[4]) == 0)  # the sample at x 0 (b 0.5) is gone
    assert trail.floor(1.0 + LAGS[4])[4] == pytest.approx(0.1)
    trail.reset()
    assert np.all(trail.floor(1.0 + LAGS[4]) == 0)


def test_a_floor_raises_only_its_legs_lift_and_not_the_parameters():
    cfg = CpgConfig()
    plain, floored = CPG(cfg, np.array([0, 1, 1, 0, 0, 1])), CPG(cfg, np.array([0, 1, 1, 0, 0, 1]))
    floor = np.array([0.0, 0.0, 0.0, 0.0, 0.45, 0.45])
    a = plain.advance(np.zeros(3), 1 / 120, 60)
    b = floored.advance(np.zeros(3), 1 / 120, 60, floor)
    np.testing.assert_array_equal(a[:, :4], b[:, :4])
    np.testing.assert_array_equal(a[..., 0], b[..., 0])
    np.testing.assert_allclose(b[:, 4:, 1], a[:, 4:, 1] * 0.45 / cfg.initial[1])
    np.testing.assert_array_equal(plain.params, floored.params)


def _lift_only_at_the_front(follow: bool, seed: int) -> tuple[dict, float]:
    """Steer b to 0.45 rad while the base is 0.2-0.9 m along (front feet at the block at 1.0-1.3 m), else 0.15.
    Returns the last info and the most the recorded hind legs' swing height exceeded b by (rad)."""
    cpg = CpgConfig().holding(LOW_GAIT).model_copy(update={"lift_follows": follow})
    env = HexapodEnv("single_block", cpg=cpg, initial_cpg=LOW_GAIT, task=TaskConfig(sensors=()))
    env.reset(seed=seed)
    excess = 0.0
    while True:
        target = 0.45 if 0.2 <= env._last_x <= 0.9 else 0.15
        steer = np.clip(4.0 * (target - env.cpg.params[1]) - 1.5 * env.cpg.rates[1], -1.0, 1.0)
        _, _, terminated, truncated, info = env.step(np.array([0.0, steer, 0.0]))
        excess = max(excess, float(np.abs(env.state().cpg_xy[4:, 1]).max() - env.cpg.params[1]))
        if terminated or truncated:
            env.close()
            return info, excess


@pytest.mark.parametrize("seed", [0, 1])
def test_a_lift_at_the_front_legs_alone_stalls_and_the_following_lift_carries_the_rest(seed):
    alone, excess = _lift_only_at_the_front(False, seed)
    assert alone["termination"] == "stuck" and alone["distance"] < 1.3  # the middle or hind feet at the face
    assert excess < 1e-9
    following, excess = _lift_only_at_the_front(True, seed)
    assert following["termination"] == "goal"
    assert excess > 0.2  # the recorder logs the hind legs swinging with the front legs' lift, above b


def test_a_fixed_gait_is_unchanged_by_the_following_lift():
    runs = []
    for follow in (False, True):
        cpg = CpgConfig().model_copy(update={"lift_follows": follow})
        env = HexapodEnv("single_block", cpg=cpg, task=TaskConfig(sensors=(), time_limit=4.0))
        env.reset(seed=3)
        runs.append([(info["distance"], info["power"]) for info in (env.step(np.zeros(3))[4] for _ in range(60))])
        env.close()
    assert runs[0] == runs[1]
