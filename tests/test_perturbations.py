"""Lift drops (`ppo.lift_drop_rate`): the rule, the wrapper on the real env, its seeding, and train-ppo's wiring."""

from pathlib import Path

import numpy as np
import pytest

from hexpipe.config import ConfigError, load_params
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.rl.perturbations import LiftDrops, drop_chance

ROOT = Path(__file__).resolve().parents[1]
RAISE_B = np.array([0.0, 1.0, 0.0])  # the largest b acceleration


def test_drop_chance_is_a_poisson_rate() -> None:
    assert drop_chance(0.0, 0.05) == 0.0
    assert drop_chance(0.2, 0.05) == pytest.approx(0.01, rel=0.01)  # about rate x dt for a rare event
    assert drop_chance(1e9, 0.05) == 1.0
    assert drop_chance(0.5, 0.1) > drop_chance(0.5, 0.05)


def test_a_drop_puts_b_at_its_floor_with_no_rate_and_leaves_a_and_omega() -> None:
    env = LiftDrops(HexapodEnv("flat", initial_cpg=(0.3, 0.45, 4.0)), rate_hz=1e9)  # fires every step
    env.reset(seed=0)
    cpg = env.unwrapped.cpg
    _, _, _, _, info = env.step(RAISE_B)
    floor = env.unwrapped.cpg_cfg.lower[1]
    # dropped to the floor before the step, then one step of the largest push: b = floor + accel * t^2 / 2
    accel, dt = env.unwrapped.cpg_cfg.accel_limit[1], env.unwrapped.control_dt
    assert floor < cpg.params[1] <= floor + accel * dt * dt
    assert cpg.params[0] == pytest.approx(0.3) and cpg.params[2] == pytest.approx(4.0)
    assert info["lift_drops"] == 1
    env.step(RAISE_B)
    assert env.unwrapped.cpg.params[1] < floor + accel * dt * dt  # dropped again: the rate did not carry over
    env.close()


def test_without_drops_the_lift_rises_and_a_rare_rate_drops_sometimes() -> None:
    bare = HexapodEnv("flat")
    bare.reset(seed=0)
    for _ in range(10):
        bare.step(RAISE_B)
    assert bare.cpg.params[1] > 0.4  # no drop: the push lifts b from 0.2
    bare.close()
    env = LiftDrops(HexapodEnv("flat"), rate_hz=2.0)
    env.reset(seed=3)
    counts = [env.step(np.zeros(3))[4]["lift_drops"] for _ in range(40)]
    assert 0 < counts[-1] < 40 and counts == sorted(counts)  # 2 s at 2 per s: a few, never every step
    env.close()


def test_drops_are_seeded_by_reset_and_leave_the_terrain_draws_alone() -> None:
    def drop_steps(seed: int) -> tuple[list[int], tuple]:
        env = LiftDrops(HexapodEnv("varied"), rate_hz=2.0)
        env.reset(seed=seed)
        boxes = env.unwrapped.terrain.boxes
        counts = [env.step(np.zeros(3))[4]["lift_drops"] for _ in range(30)]
        env.close()
        return counts, boxes

    first, boxes = drop_steps(7)
    again, boxes_again = drop_steps(7)
    other, _ = drop_steps(8)
    assert first == again and boxes == boxes_again
    assert first != other
    bare = HexapodEnv("varied")
    bare.reset(seed=7)
    assert bare.terrain.boxes == boxes  # the wrapper draws nothing from the env's np_random
    bare.close()


def test_the_rate_is_checked_once_in_config() -> None:
    with pytest.raises(ConfigError, match="lift_drop_rate"):
        load_params(ROOT / "params.yaml", ["ppo.lift_drop_rate=-1"])
    with pytest.raises(ValueError, match="rate_hz"):
        LiftDrops(HexapodEnv("flat"), rate_hz=0.0)


def test_train_ppo_wraps_its_envs_only_when_asked() -> None:
    from hexpipe.rl.train import env_factory

    off = load_params(ROOT / "params.yaml", ["ppo.curriculum=false"])
    on = load_params(ROOT / "params.yaml", ["ppo.curriculum=false", "ppo.lift_drop_rate=0.5"])
    bare, wrapped = env_factory(off, "flat", None, False)(), env_factory(on, "flat", None, False)()
    assert isinstance(bare, HexapodEnv) and isinstance(wrapped, LiftDrops)
    assert wrapped.chance == pytest.approx(drop_chance(0.5, 1 / on.sim.control_hz))
    bare.close()
    wrapped.close()
