"""The lift reflex (task.lift_reflex): its zone on the height map, its ramp, and what it does to a low gait; and the
same reflex as a teacher (task.lift_teacher), which prices b's shortfall below it and moves no leg."""

import math

import numpy as np
import pytest
from held_gait import walk_held

from hexpipe.config import ConfigError, Params, SensorConfig, TaskConfig, apply_overrides, reflex_zone
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.envs.rewards import lift_shortfall_penalty
from hexpipe.sim.lift_reflex import lift_reflex, map_relief
from hexpipe.sim.zone_reflex import ramp_toward, zone_mask

LOW_GAIT = (0.25, 0.15, 1.5 * math.pi)  # stopped by the 0.10 m block (tests/test_env.py, the premise)
REFLEX = TaskConfig(sensors=(), lift_reflex=True)  # a blind policy: only the reflex reads the map
TEACHER = TaskConfig(sensors=(), lift_teacher=30.0)


def test_the_zone_is_the_cells_from_behind_the_hind_feet_to_ahead_of_the_front_feet_across_the_legs():
    # the default map: 32 rows of 6.25 cm from 0.6 m behind the base, 32 columns of 5 cm across 1.6 m
    mask = zone_mask(-0.6, 1.4, 32, 32, 1.6, behind=0.6, ahead=0.7)
    rows, cols = np.nonzero(mask.any(axis=1))[0], np.nonzero(mask.any(axis=0))[0]
    assert rows.tolist() == list(range(21))  # row 20's centre is at 0.681 m, row 21's at 0.744 m
    assert cols.tolist() == list(range(10, 22))  # centres from -0.275 m to +0.275 m
    assert mask.sum() == 21 * 12
    assert np.array_equal(reflex_zone(SensorConfig(), TaskConfig().lift_zone), mask)


def test_relief_is_rise_minus_fall_inside_the_zone_only():
    mask = zone_mask(-0.6, 1.4, 32, 32, 1.6, behind=0.6, ahead=0.7)
    level = np.zeros((32, 32), dtype=np.float32)
    assert map_relief(level + 0.37, mask) == 0.0  # any reference height: level ground has no relief
    beyond = level.copy()
    beyond[25:, :] = 0.10  # a block whose face is beyond the zone
    assert map_relief(beyond, mask) == 0.0
    inside = level.copy()
    inside[18:, :] = 0.10  # ... and once the face is in the zone
    assert map_relief(inside, mask) == pytest.approx(0.10)


def test_the_reflex_ramps_at_bs_own_rates_toward_the_ceiling_near_relief_and_the_floor_elsewhere():
    assert ramp_toward(0.2, 0.5, rise=1.0, fall=0.1, dt=0.05) == pytest.approx(0.25)
    assert ramp_toward(0.48, 0.5, rise=1.0, fall=0.1, dt=0.05) == 0.5
    assert ramp_toward(0.5, 0.2, rise=1.0, fall=0.1, dt=0.05) == pytest.approx(0.495)
    mask = zone_mask(-0.6, 1.4, 32, 32, 1.6, behind=0.6, ahead=0.7)
    reflex = lift_reflex(mask, relief=0.03, floor=0.2, ceiling=0.5, rise=1.0, fall=1.0)
    flat, block = np.zeros((32, 32)), np.zeros((32, 32))
    block[15:, :] = 0.04
    reflex.see(flat)
    assert [reflex.advance(0.05) for _ in range(3)] == [0.2, 0.2, 0.2]
    reflex.see(block)
    up = [reflex.advance(0.05) for _ in range(8)]
    assert up[:6] == pytest.approx([0.25, 0.30, 0.35, 0.40, 0.45, 0.50]) and up[6:] == [0.5, 0.5]
    reflex.see(block * 0.5)  # 2 cm: below the 3 cm that counts as uneven
    assert reflex.advance(0.05) == pytest.approx(0.45)
    reflex.reset()
    assert reflex.level == 0.2 and not reflex.triggered


def test_a_zone_with_no_cell_on_the_map_is_refused():
    with pytest.raises(ValueError, match="no height-map cell"):
        lift_reflex(np.zeros((4, 4), dtype=bool), 0.03, 0.2, 0.5, 1.0, 1.0)


def test_the_setting_is_refused_in_one_line_without_a_zone_or_with_a_zone_off_the_map():
    with pytest.raises(ConfigError, match=r"task: lift_reflex .*lift_free_zone, which is null") as exc:
        apply_overrides(Params(), ["task.lift_reflex=true", "task.lift_free_zone=null"])
    assert "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match="lies outside the height map") as exc:
        apply_overrides(Params(), ["task.lift_reflex=true", "sensors.heightmap_ahead=[0.8, 2.0]"])
    assert "\n" not in str(exc.value)
    assert apply_overrides(Params(), ["task.lift_reflex=true"]).task.lift_reflex


def _walk(terrain: str, task: TaskConfig, seed: int = 0) -> tuple[dict, list[tuple[float, float, float]]]:
    """A rollout of the held low gait: its last info and (base x, b, lift) at every step."""
    return walk_held(terrain, LOW_GAIT, task, lambda x, info: (x, float(info["cpg"][1]), info["lift"]), seed=seed)


def test_the_reflex_carries_the_low_gait_over_the_block_it_stops_without_one():
    """The premise says the 0.10 m block stops b = 0.15; with the reflex the same gait (b never changes) lifts
    from about 0.7 m before the face and crosses. A blind policy's env: only the reflex reads the height map."""
    info, trace = _walk("single_block", REFLEX)
    assert info["termination"] == "goal"
    assert all(b == pytest.approx(LOW_GAIT[1]) for _, b, _ in trace)  # the policy's b is untouched
    assert all(lift == pytest.approx(0.15) for x, _, lift in trace if x < 0.2)  # open ground: the gait's own lift
    assert max(lift for x, _, lift in trace if 0.3 < x < 1.0) == pytest.approx(0.5)  # b's ceiling before the face
    assert all(lift == pytest.approx(0.15) for x, _, lift in trace if x > 2.4)  # the block well behind: down again


def test_the_reflex_never_lifts_on_flat_ground():
    info, trace = _walk("flat", REFLEX)
    assert info["termination"] == "goal"
    assert all(lift == pytest.approx(0.15) for _, _, lift in trace)


def test_the_reflex_reads_the_map_without_putting_it_in_a_blind_observation():
    env = HexapodEnv("single_block", task=REFLEX)
    obs, _ = env.reset(seed=0)
    assert set(obs) == {"body", "cpg"} and env.observation_space.contains(obs)
    env.close()


def test_the_teacher_charges_only_the_shortfall_below_the_reflexs_lift():
    assert lift_shortfall_penalty(0.2, 0.5, 30.0) == pytest.approx(-9.0)
    assert lift_shortfall_penalty(0.5, 0.5, 30.0) == 0.0
    assert lift_shortfall_penalty(0.45, 0.3, 30.0) == 0.0  # above the reflex: the lift price's business, not this
    assert lift_shortfall_penalty(0.2, 0.5, 0.0) == 0.0


def test_the_teacher_is_refused_in_one_line_without_a_zone_and_named():
    with pytest.raises(ConfigError, match=r"task: lift_teacher .*lift_free_zone, which is null") as exc:
        apply_overrides(Params(), ["task.lift_teacher=30", "task.lift_free_zone=null"])
    assert "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match="lift_teacher sees none of it"):
        apply_overrides(Params(), ["task.lift_teacher=30", "sensors.heightmap_ahead=[0.8, 2.0]"])
    with pytest.raises(ConfigError, match="lift_teacher"):
        apply_overrides(Params(), ["task.lift_teacher=-1"])


def test_the_teacher_asks_for_a_lift_before_the_block_and_moves_no_leg():
    """The held low gait under the teacher: nothing charged on open ground, the shortfall charged before the face,
    the legs at the gait's own lift throughout, so the block stops it as it does without the teacher."""
    info, steps = walk_held("single_block", LOW_GAIT, TEACHER,
                            lambda x, info: (x, info["reward_terms"]["teacher"], info["lift"]))
    assert info["termination"] != "goal"
    assert all(lift == pytest.approx(LOW_GAIT[1]) for _, _, lift in steps)
    assert all(t == 0.0 for x, t, _ in steps if x < 0.2)
    assert min(t for x, t, _ in steps if x > 0.3) == pytest.approx(-30.0 * (0.5 - LOW_GAIT[1]))


def test_runs_without_the_teacher_log_the_terms_they_always_did():
    env = HexapodEnv("flat", task=TaskConfig(sensors=(), lift_teacher=0.0))  # the teacher is on by default
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.zeros(3))
    env.close()
    assert set(info["reward_terms"]) == {"forward", "power", "lift", "failure"}


NEAR = TaskConfig(sensors=(), lift_reflex=True, lift_reflex_zone=(0.2, 0.7))  # the lift reflex's own, shorter zone


def test_a_zone_of_its_own_moves_only_the_lift_reflex():
    """task.lift_reflex_zone is what the lift reflex reads; the stride reflex keeps lift_free_zone."""
    env = HexapodEnv("flat", task=NEAR.model_copy(update={"stride_reflex": 0.3}))
    sensors = SensorConfig()
    assert np.array_equal(env.reflex.mask, reflex_zone(sensors, (0.2, 0.7)))
    assert np.array_equal(env.stride_reflex.mask, reflex_zone(sensors, (0.6, 0.7)))
    assert env.reflex.mask.sum() < env.stride_reflex.mask.sum()
    env.close()


def test_a_zone_of_its_own_drops_the_lift_sooner_past_the_block_and_still_crosses():
    """The default zone reaches 0.6 m behind the base, so the legs swing high until the hind feet are well past the
    block; 0.2 m behind lets the lift down about 0.4 m sooner. Both start lifting where the face enters 0.7 m
    ahead, and both carry the low gait across."""
    lifted = {}
    for name, task in (("default", REFLEX), ("near", NEAR)):
        info, trace = _walk("single_block", task)
        assert info["termination"] == "goal"
        lifted[name] = [x for x, _, lift in trace if lift > LOW_GAIT[1] + 1e-6]
    assert min(lifted["near"]) == pytest.approx(min(lifted["default"]), abs=0.02)
    assert 0.3 < max(lifted["default"]) - max(lifted["near"]) < 0.5


def test_a_zone_of_its_own_is_refused_in_one_line_when_no_reflex_reads_it_or_it_lies_off_the_map():
    with pytest.raises(ConfigError, match=r"lift_reflex_zone \[0.2, 0.7\] .*neither lift_reflex nor lift_teacher") \
            as exc:
        apply_overrides(Params(), ["task.lift_teacher=0", "task.lift_reflex_zone=[0.2, 0.7]"])
    assert "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match=r"task.lift_reflex_zone \[0.0, 0.0\] lies outside the height map") as exc:
        apply_overrides(Params(), ["task.lift_reflex=true", "task.lift_reflex_zone=[0, 0]"])
    assert "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match="lift_reflex_zone"):
        apply_overrides(Params(), ["task.lift_reflex=true", "task.lift_reflex_zone=[-0.1, 0.7]"])
    # its own zone stands in for a null lift_free_zone, since only the lift price then reads that
    params = apply_overrides(Params(), ["task.lift_reflex=true", "task.lift_reflex_zone=[0.2, 0.7]",
                                        "task.lift_free_zone=null", "task.lift_teacher=0"])
    assert params.task.lift_zone == (0.2, 0.7)


def test_a_relief_scale_asks_a_low_step_for_less_lift_and_a_full_block_for_the_ceiling():
    """task.lift_reflex_relief: at 0.10 m a 6 cm rise asks 0.6 of the way from b's floor to its ceiling, a 10 cm
    block (or taller) all of it, and 2 cm, under the 3 cm that counts as uneven, nothing."""
    mask = zone_mask(-0.6, 1.4, 32, 32, 1.6, behind=0.6, ahead=0.7)
    reflex = lift_reflex(mask, relief=0.03, floor=0.2, ceiling=0.5, rise=10.0, fall=10.0, full_relief=0.10)
    levels = {}
    for height in (0.02, 0.06, 0.10, 0.12):
        block = np.zeros((32, 32))
        block[15:, :] = height
        reflex.see(block)
        levels[height] = reflex.advance(0.05)
    assert levels == pytest.approx({0.02: 0.2, 0.06: 0.38, 0.10: 0.5, 0.12: 0.5})
    unscaled = lift_reflex(mask, relief=0.03, floor=0.2, ceiling=0.5, rise=10.0, fall=10.0)
    block = np.zeros((32, 32))
    block[15:, :] = 0.06
    unscaled.see(block)
    assert unscaled.advance(0.05) == 0.5  # null: the ceiling for any relief over 3 cm


def test_the_teacher_with_a_relief_scale_asks_the_low_block_for_less_than_the_single_block():
    """In the env: the teacher's largest charge before the low block's 6 cm face is about 0.6 of the single block's
    (the map reads the face at 5.3 cm: the lift asked is 0.2 + 0.53 * 0.3 = 0.36 rad against 0.5)."""
    task = TEACHER.model_copy(update={"lift_reflex_relief": 0.10})
    worst = {}
    for terrain in ("single_block", "low_block"):
        _, steps = walk_held(terrain, LOW_GAIT, task, lambda x, info: (x, info["reward_terms"]["teacher"]))
        worst[terrain] = min(t for x, t in steps if 0.3 < x < 0.9)
    assert worst["single_block"] == pytest.approx(-30.0 * (0.5 - LOW_GAIT[1]))
    assert 0.5 < worst["low_block"] / worst["single_block"] < 0.7


def test_a_relief_scale_is_refused_in_one_line_when_no_reflex_reads_it_or_it_is_under_3_cm():
    with pytest.raises(ConfigError, match=r"lift_reflex_relief 0.1 .*neither lift_reflex nor lift_teacher") as exc:
        apply_overrides(Params(), ["task.lift_teacher=0", "task.lift_reflex_relief=0.1"])
    assert "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match="lift_reflex_relief") as exc:
        apply_overrides(Params(), ["task.lift_reflex_relief=0.02"])
    assert "\n" not in str(exc.value)
    assert apply_overrides(Params(), ["task.lift_reflex_relief=0.1"]).task.lift_reflex_relief == 0.1
