"""The elevator reflex (hexpipe/sim/elevator.py): which legs count as caught, how far their elbows open, and that it
changes nothing on flat ground and frees a fixed gait at the wide block's face."""

from __future__ import annotations

import numpy as np
import pytest

from hexpipe.config import CpgConfig, SimConfig
from hexpipe.sim.elevator import caught_legs, elbow_opening, pressed_from_side

UP = np.array([[0.0, 0.0, 1.0]])
FACE = np.array([[-1.0, 0.0, 0.0]])  # a block's face pressing back at the robot
NONE = np.zeros((0, 3))


def test_only_a_push_from_the_side_counts() -> None:
    edge = np.array([[-0.8, 0.0, 0.6]])  # 37 degrees above horizontal: an edge, not the ground
    slope = np.array([[0.3, 0.0, 0.95]])  # rough ground's bump
    assert pressed_from_side([UP, FACE, NONE, edge, slope, np.vstack([UP, FACE])]).tolist() == [
        False, True, False, True, False, True]


def test_a_caught_leg_stays_caught_until_its_stance() -> None:
    y = np.array([0.3, 0.3, -0.1, 0.2, 0.0, 0.4])
    pressed = np.array([True, False, True, False, False, False])
    caught = caught_legs(np.zeros(6, bool), y, pressed)
    assert caught.tolist() == [True, False, False, False, False, False]  # a leg in stance is never caught
    caught = caught_legs(caught, np.array([0.1, 0.3, 0.2, 0.2, 0.1, 0.4]), np.zeros(6, bool))
    assert caught.tolist() == [True, False, False, False, False, False]  # still swinging: still caught
    caught = caught_legs(caught, np.array([-0.05, 0.3, 0.2, 0.2, 0.1, 0.4]), np.zeros(6, bool))
    assert not caught.any()  # its stance releases it


def test_the_elbow_opens_with_the_lift_in_a_caught_swing_only() -> None:
    y = np.array([[0.4, 0.4, -0.2, 0.1, 0.0, 0.2]])
    caught = np.array([True, False, True, True, False, False])
    np.testing.assert_allclose(elbow_opening(y, caught, 1.5), [[0.6, 0.0, 0.0, 0.15, 0.0, 0.0]])


def _walk(terrain: str, gain: float) -> tuple[int, float, int]:
    from hexpipe.envs.hexapod import HexapodEnv

    cpg = CpgConfig(lower=[0.6, 0.2, 3.141593], upper=[0.6, 0.5, 4.712389], initial=[0.6, 0.5, 4.712389])
    env = HexapodEnv(terrain=terrain, sim=SimConfig(elevator_gain=gain), cpg=cpg)
    try:
        env.reset(seed=3)
        caught = 0
        for step in range(1, 401):
            _, _, terminated, truncated, _ = env.step(np.zeros(3))
            caught += int(env._caught.sum())
            if terminated or truncated:
                return step, float(env._last_x), caught
        return step, float(env._last_x), caught
    finally:
        env.close()


def test_flat_ground_never_triggers_it() -> None:
    assert _walk("flat", 1.5) == _walk("flat", 0.0)


@pytest.mark.parametrize("gain", [1.5])
def test_it_opens_at_the_wide_blocks_face(gain: float) -> None:
    _, x, caught = _walk("wide_block", gain)
    assert caught > 0 and x >= 3.0
