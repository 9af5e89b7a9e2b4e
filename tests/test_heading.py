"""The heading reflex (hexpipe/sim/heading.py): which side shortens its stride, by how much, and that it turns a
walking robot back onto the course."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hexpipe.config import CpgConfig, SimConfig
from hexpipe.sim.heading import MAX_CHANGE, stride_scales

SIDE = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0])  # left, right, ... as GaitMap.yaw_sign


def test_turned_right_the_left_side_shortens() -> None:
    np.testing.assert_allclose(stride_scales(-0.2, SIDE, 1.0), [0.8, 1.2, 0.8, 1.2, 0.8, 1.2])
    np.testing.assert_allclose(stride_scales(0.1, SIDE, 2.0), [1.2, 0.8, 1.2, 0.8, 1.2, 0.8])


def test_the_change_is_clipped_and_the_yaw_wrapped() -> None:
    np.testing.assert_allclose(stride_scales(-1.5, SIDE, 1.0), 1.0 + SIDE * -MAX_CHANGE)
    np.testing.assert_allclose(stride_scales(2 * math.pi - 0.1, SIDE, 1.0), stride_scales(-0.1, SIDE, 1.0))
    np.testing.assert_allclose(stride_scales(0.4, SIDE, 0.0), np.ones(6))


def test_gain_zero_is_the_gait_without_the_reflex() -> None:
    from hexpipe.sim.gait import GaitMap
    from hexpipe.sim.robot import RobotSpec

    gait = GaitMap(RobotSpec(), 0.24, 0.30, 1.4)
    xy = np.random.default_rng(0).uniform(-0.6, 0.6, size=(4, 6, 2))
    np.testing.assert_array_equal(gait.joint_targets(xy), gait.joint_targets(xy, None, stride_scales(0.3, SIDE, 0)))


def _yaw_after_turn(gain: float, turn: float, steps: int = 160) -> float:
    """Base yaw (rad) after `steps` control steps of a fixed gait on flat ground, started turned by `turn` rad."""
    import pybullet as p

    from hexpipe.envs.hexapod import HexapodEnv
    from hexpipe.sensors.heightmap import quat_to_yaw

    cpg = CpgConfig(initial=[0.4, 0.4, 3.141593])
    env = HexapodEnv(terrain="flat", sim=SimConfig(heading_gain=gain), cpg=cpg)
    try:
        env.reset(seed=0)
        pos, _, _, _ = env.robot.base_state()
        p.resetBasePositionAndOrientation(env.robot.body, pos, p.getQuaternionFromEuler([0, 0, turn]),
                                          physicsClientId=env.client)
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(np.zeros(3))
            if terminated or truncated:
                break
        return quat_to_yaw(env.robot.base_state()[1])
    finally:
        env.close()


@pytest.mark.parametrize("turn", [1.0, -1.0])
def test_it_turns_the_robot_back_onto_the_course(turn: float) -> None:
    """Turned 1 rad, the gait alone drifts further, towards walking sideways (yaw +-pi/2, as the two elev150
    episodes that stalled past a block did); the reflex brings it back within 0.2 rad in 8 s."""
    held, steered = _yaw_after_turn(0.0, turn), _yaw_after_turn(1.0, turn)
    assert abs(held) > 1.2 and np.sign(held) == np.sign(turn)
    assert abs(steered) < 0.2
