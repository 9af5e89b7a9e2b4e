"""The stride reflex: what counts as a straddle on the height map, its ramp; the teacher in the env
(task.stride_teacher), which prices a's distance from the reflex's stride and moves no leg; and the leg mover
(task.stride_reflex), which caps the legs' stride at the straddle and leaves the policy's a alone."""

import numpy as np
import pytest
from held_gait import walk_held

from hexpipe.config import ConfigError, CpgConfig, Params, TaskConfig, apply_overrides
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.envs.rewards import stride_deviation_penalty
from hexpipe.sim.cpg import CPG
from hexpipe.sim.stride_reflex import raised_regions, stride_reflex
from hexpipe.sim.zone_reflex import zone_mask

MASK = zone_mask(-0.6, 1.4, 32, 32, 1.6, behind=0.6, ahead=0.7)  # the default map and zone: rows 0-20
GAIT = (0.4, 0.5, 3.141593)  # the fixed gait's stride and cycle at b's ceiling
BOUNDS = CpgConfig(lower=(0.35, 0.2, 3.141593), upper=(0.4, 0.5, 3.141593), initial=GAIT)  # a free in [0.35, 0.4]
TEACHER = TaskConfig(sensors=(), stride_teacher=100.0)  # a blind policy: only the reflex reads the map


def _map(*blocks: tuple[int, int, float]) -> np.ndarray:
    """A level map 0.37 m below the reference with a block across every column for each (first row, end row, m)."""
    heights = np.full((32, 32), -0.37, dtype=np.float32)
    for first, end, height in blocks:
        heights[first:end, :] += height
    return heights


def test_a_straddle_is_two_raised_regions_inside_the_zone():
    assert raised_regions(_map(), MASK) == 0
    assert raised_regions(_map((4, 9, 0.10)), MASK) == 1
    assert raised_regions(_map((4, 9, 0.10), (16, 21, 0.10)), MASK) == 2
    assert raised_regions(_map((4, 9, 0.10), (24, 29, 0.10)), MASK) == 1  # the second block beyond the zone
    assert raised_regions(_map((4, 9, 0.10), (16, 21, 0.04)), MASK) == 1  # 4 cm: a bump, not a block
    assert raised_regions(_map((0, 21, 0.10)), MASK) == 0  # standing on one long block: level under the zone
    assert raised_regions(_map((4, 21, 0.06), (8, 12, 0.06)), MASK) == 1  # a step on a step: one raised run


def test_the_reflex_ramps_at_as_own_rates_to_the_short_stride_at_a_straddle_only():
    reflex = stride_reflex(MASK, short=0.35, long=0.4, rise=1.0, fall=0.5)
    reflex.see(_map((4, 9, 0.10)))
    assert [reflex.advance(0.05) for _ in range(2)] == [0.4, 0.4]  # one face: the long stride
    reflex.see(_map((4, 9, 0.10), (16, 21, 0.10)))
    down = [reflex.advance(0.05) for _ in range(3)]
    assert down == pytest.approx([0.375, 0.35, 0.35])  # at the fall rate, 0.5 rad/s
    reflex.see(_map())
    assert reflex.advance(0.02) == pytest.approx(0.37)  # back up at the rise rate, 1 rad/s
    reflex.reset()
    assert reflex.level == 0.4 and not reflex.triggered
    with pytest.raises(ValueError, match="no height-map cell"):
        stride_reflex(np.zeros((4, 4), dtype=bool), 0.35, 0.4, 1.0, 1.0)


def test_the_teacher_charges_as_distance_from_the_reflex_both_ways():
    assert stride_deviation_penalty(0.4, 0.35, 100.0) == pytest.approx(-5.0)
    assert stride_deviation_penalty(0.35, 0.4, 100.0) == pytest.approx(-5.0)
    assert stride_deviation_penalty(0.38, 0.38, 100.0) == 0.0
    assert stride_deviation_penalty(0.35, 0.4, 0.0) == 0.0


def _walk(terrain: str) -> tuple[dict, list[tuple[float, float, float]]]:
    """The held long gait under the stride teacher: its last info and (base x, a, stride term) at every step."""
    return walk_held(terrain, GAIT, TEACHER, lambda x, info: (x, float(info["cpg"][0]), info["reward_terms"]["stride"]),
                     cpg=BOUNDS)


def test_the_teacher_asks_for_the_short_stride_between_extra_blocks_and_moves_no_leg():
    """Extra blocks' faces are at 1.0 m and 2.0 m, 0.3 m deep: both lie within the zone (0.6 m behind the base to
    0.7 m ahead) while the base is between 1.3 m and 1.9 m. The held gait's a never changes."""
    info, trace = _walk("extra_blocks")
    assert info["termination"] == "goal"
    assert all(a == pytest.approx(GAIT[0]) for _, a, _ in trace)
    assert all(term == 0.0 for x, _, term in trace if x < 1.2 or x > 2.1)
    assert min(term for x, _, term in trace if 1.4 < x < 1.8) == pytest.approx(-100.0 * 0.05)


def test_the_teacher_never_asks_for_a_short_stride_at_one_block():
    info, trace = _walk("single_block")
    assert info["termination"] == "goal"
    assert all(term == 0.0 for _, _, term in trace)


def test_the_stride_teacher_is_refused_in_one_line_when_it_cannot_teach():
    both = r"task: lift_teacher and stride_teacher read the terrain in lift_free_zone, which is null"
    with pytest.raises(ConfigError, match=both) as exc:
        apply_overrides(Params(), ["task.stride_teacher=100", "task.lift_free_zone=null"])
    assert "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match=r"stride_teacher .*cpg.lower's a .*cpg.upper's a") as exc:
        apply_overrides(Params(), ["task.stride_teacher=100", "cpg.lower=[0.4,0.2,1.0]", "cpg.upper=[0.4,0.5,6.0]",
                                   "cpg.initial=[0.4,0.2,4.0]"])
    assert "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match="stride_teacher"):
        apply_overrides(Params(), ["task.stride_teacher=-1"])
    with pytest.raises(ConfigError, match="stride_teacher sees none of it"):
        apply_overrides(Params(), ["task.lift_teacher=0", "task.stride_teacher=100",
                                   "sensors.heightmap_ahead=[0.8, 2.0]"])
    assert apply_overrides(Params(), ["task.stride_teacher=100"]).task.stride_teacher == 100.0


def test_runs_without_the_stride_teacher_log_no_stride_term():
    env = HexapodEnv("flat", task=TaskConfig(sensors=()))
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.zeros(3))
    env.close()
    assert "stride" not in info["reward_terms"]


REFLEX_GAIT = (0.4, 0.45, 3.141593)  # the fixed gait's stride and cycle at a lift that fails the straddle


def _reflex_walk(terrain: str, cap: float, seed: int) -> tuple[dict, list[tuple[float, float]]]:
    """The held gait (a 0.4, b 0.45) with the stride reflex at `cap` (0: off): its last info and (base x, the
    legs' stride) at every step; the policy's a is checked to stay the gait's, and no stride term charged."""

    def row(x: float, info: dict) -> tuple[float, float]:
        assert float(info["cpg"][0]) == pytest.approx(REFLEX_GAIT[0]) and "stride" not in info["reward_terms"]
        return x, info["stride"]

    return walk_held(terrain, REFLEX_GAIT, TaskConfig(sensors=(), stride_reflex=cap), row, seed=seed)


def test_the_cpg_swings_the_legs_with_the_shorter_of_a_and_the_stride_cap():
    cpg = CPG(CpgConfig().holding(REFLEX_GAIT), np.array([0, 1, 0, 1, 0, 1]))
    cpg.reset(np.array(REFLEX_GAIT))
    free, capped = CPG(cpg.cfg, np.array([0, 1, 0, 1, 0, 1])), cpg
    free.reset(np.array(REFLEX_GAIT))
    xy_free = free.advance(np.zeros(3), 0.01, 20)
    xy_capped = capped.advance(np.zeros(3), 0.01, 20, stride_cap=0.35)
    assert np.allclose(xy_capped[..., 0], xy_free[..., 0] * 0.35 / 0.4)  # the stride scaled, the phase the same
    assert np.allclose(xy_capped[..., 1], xy_free[..., 1])  # the lift untouched
    assert capped.params[0] == pytest.approx(0.4)  # the parameter itself is unchanged
    assert np.allclose(free.advance(np.zeros(3), 0.01, 5), capped.advance(np.zeros(3), 0.01, 5, stride_cap=0.45))


STRADDLE = (1.3, 1.7)  # m: where the base stops when the front feet meet the second block's face mid-straddle


def test_the_stride_reflex_carries_the_long_stride_over_the_straddle_it_stalls_at_without_one():
    """The premise of task.stride_reflex: at a 0.4, b 0.45 the straddle of extra blocks stops the gait (base at
    about 1.5 m) on some physics seeds: 7 of 30 on each of two CPU kinds, but not the same seeds, since PyBullet's
    floats differ across CPUs (reports/experiments/stride_reflex/premise.txt on family 26, premise_family25.txt on
    family 25). So the stalled seeds are found among the first 15, not named: the same gait, its stride capped at
    0.35 only while both blocks lie in the zone (base at 1.3-1.9 m), stops at the straddle on none of them and
    reaches the goal on most."""
    stalled = []
    for seed in range(15):
        info, _ = _reflex_walk("extra_blocks", 0.0, seed)
        if info["termination"] == "stuck" and STRADDLE[0] < info["distance"] < STRADDLE[1]:
            stalled.append(seed)
    assert len(stalled) >= 2, f"the straddle stopped the long stride on seeds {stalled} of 0-14 only"
    crossed = 0
    for seed in stalled[:3]:
        info, trace = _reflex_walk("extra_blocks", 0.35, seed)
        assert not STRADDLE[0] < info["distance"] < STRADDLE[1], f"seed {seed} still stops at the straddle"
        crossed += info["termination"] == "goal"
        assert all(stride == pytest.approx(0.4) for x, stride in trace if x < 1.2 or x > 2.1)
        assert all(stride == pytest.approx(0.35) for x, stride in trace if 1.45 < x < 1.75)
    assert crossed >= 2, f"the capped stride reached the goal on {crossed} of seeds {stalled[:3]}"


def test_the_stride_reflex_keeps_the_long_stride_at_one_block():
    info, trace = _reflex_walk("single_block", 0.35, 0)
    assert info["termination"] == "goal"
    assert all(stride == pytest.approx(0.4) for _, stride in trace)


def test_the_stride_reflex_is_refused_in_one_line_when_it_cannot_shorten_the_stride():
    with pytest.raises(ConfigError, match=r"task.stride_reflex \(0.45\) .*shorter than cpg.upper's a \(0.4\)") as exc:
        apply_overrides(Params(), ["task.stride_reflex=0.45"])
    assert "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match=r"task: lift_teacher and stride_reflex read .*lift_free_zone, which is null"):
        apply_overrides(Params(), ["task.stride_reflex=0.35", "task.lift_free_zone=null"])
    with pytest.raises(ConfigError, match="stride_reflex"):
        apply_overrides(Params(), ["task.stride_reflex=-0.1"])
    # the short stride may lie below a's floor: the reflex moves the legs, not the policy's a
    pinned = ["cpg.lower=[0.4,0.2,3.141593]", "cpg.upper=[0.4,0.5,3.141593]", "cpg.initial=[0.4,0.2,3.141593]"]
    assert apply_overrides(Params(), ["task.stride_reflex=0.35", *pinned]).task.stride_reflex == 0.35
