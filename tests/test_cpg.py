"""The CPG: convergence to the ellipse, period, tripod phase locking, continuity, parameter bounds."""

import math

import numpy as np
import pytest

from hexpipe.config import CpgConfig
from hexpipe.sim.cpg import (
    CPG,
    coupling_flows,
    coupling_matrix,
    integrate_parameters,
    locked_states,
    parameter_path,
    radial_flow,
    tripod_phases,
)
from hexpipe.sim.gait import GaitMap, leg_ik, slew_limit, slew_path
from hexpipe.sim.robot import RobotSpec

TRIPODS = np.array([leg.tripod for leg in RobotSpec().legs])
DT = 1 / 240


def run(cpg: CPG, seconds: float, accel: np.ndarray | None = None) -> list[np.ndarray]:
    accel = np.zeros(3) if accel is None else accel
    return [cpg.step(accel, DT).copy() for _ in range(round(seconds / DT))]


def ellipse_residual(xy: np.ndarray, a: float, b: float) -> np.ndarray:
    return np.abs((xy[:, 0] / a) ** 2 + (xy[:, 1] / b) ** 2 - 1)


def test_off_cycle_starts_converge_to_ellipse():
    rng = np.random.default_rng(0)
    cpg = CPG(CpgConfig(), TRIPODS)
    cpg.reset(cpg.params, z=rng.uniform(-2.5, 2.5, size=(6, 2)) + 0.05)
    a, b, _ = cpg.params
    start = ellipse_residual(cpg.xy, a, b)
    assert start.max() > 0.5
    run(cpg, 2.0)
    assert ellipse_residual(cpg.xy, a, b).max() < 1e-3


def test_period_matches_omega():
    cfg = CpgConfig()
    cpg = CPG(cfg, TRIPODS)
    omega = cfg.initial[2]
    ys = np.array([xy[0, 1] for xy in run(cpg, 4 * 2 * math.pi / omega)])
    crossings = np.flatnonzero((ys[:-1] < 0) & (ys[1:] >= 0))
    # sub-sample crossing times by linear interpolation
    times = (crossings + ys[crossings] / (ys[crossings] - ys[crossings + 1])) * DT
    period = np.diff(times).mean()
    assert period == pytest.approx(2 * math.pi / omega, rel=0.02)


def test_tripods_lock_from_random_phases():
    rng = np.random.default_rng(1)
    cpg = CPG(CpgConfig(), TRIPODS)
    theta = rng.uniform(0, 2 * math.pi, 6)
    cpg.reset(cpg.params, z=np.stack([np.cos(theta), np.sin(theta)], 1))
    run(cpg, 10.0)
    phase = np.arctan2(cpg.z[:, 1], cpg.z[:, 0])
    rel = np.angle(np.exp(1j * (phase - phase[0])))
    expected = np.angle(np.exp(1j * (tripod_phases(TRIPODS) - tripod_phases(TRIPODS)[0])))
    assert np.allclose(np.abs(np.angle(np.exp(1j * (rel - expected)))), 0, atol=0.05)


def test_locked_coupling_does_not_change_the_cycle():
    phases = tripod_phases(TRIPODS)
    coupling = coupling_matrix(phases, 4.0)
    assert np.allclose(coupling @ locked_states(phases, 0.7), 0.0, atol=1e-12)
    flows = coupling_flows(coupling, DT, 12)
    assert np.allclose(flows @ locked_states(phases, 0.7), locked_states(phases, 0.7), atol=1e-12)
    # off lock, the coupling pulls the tripods together: the anti-locked mode decays
    assert np.abs(flows[-1] @ np.ones(6)).max() < np.abs(np.ones(6)).max()


def test_radial_flow_is_the_exact_logistic_solution():
    w = np.array([0.1 + 0.2j, 2.0 - 1.0j, 1.0 + 0.0j, 0.0j])
    t = np.array([1e-3, 0.05, 1.0])
    out = radial_flow(w, 10.0, t)
    assert np.allclose(np.angle(out[:, :3]), np.angle(w[:3]))  # the phase is kept
    assert np.allclose(np.abs(out[:, 2]), 1.0) and np.allclose(out[:, 3], 0.0)  # fixed points
    # against many tiny Euler steps of dw/dt = gamma (1 - |w|^2) w
    euler = w.copy()
    for _ in range(50_000):
        euler = euler + 1e-6 * 10.0 * (1 - np.abs(euler) ** 2) * euler
    assert np.allclose(out[1], euler, atol=1e-4)


def test_advance_plans_a_control_step_like_single_steps():
    cfg = CpgConfig()
    one, many = CPG(cfg, TRIPODS), CPG(cfg, TRIPODS)
    accel = np.array([4.0, -4.0, 40.0])
    singles = np.array([one.step(accel, DT) for _ in range(12)])
    planned = many.advance(accel, DT, 12)
    assert planned.shape == (12, 6, 2)
    assert np.allclose(planned, singles, atol=1e-9)  # locked: both are the exact rotation
    assert np.array_equal(one.params, many.params) and np.array_equal(one.rates, many.rates)


@pytest.mark.parametrize(
    "cfg",
    [CpgConfig(fall_rate_limit=None), CpgConfig(fall_rate_limit=(0.5, 0.1, 2.0)),
     CpgConfig(fall_rate_limit=(0.5, 0.1, 2.0), action_order=1)],
    ids=["symmetric", "slow_fall", "first_order"],
)
def test_parameter_path_equals_repeated_integration(cfg):
    rng = np.random.default_rng(2)
    values, rates = np.asarray(cfg.initial), np.zeros(3)
    scale = np.asarray(cfg.rate_limit if cfg.action_order == 1 else cfg.accel_limit)
    for _ in range(300):  # random commands drive the values into their bounds and back
        accel = rng.uniform(-1, 1, 3) * scale
        path_v, path_r = parameter_path(values, rates, accel, DT, 12, cfg)
        for k in range(12):
            values, rates = integrate_parameters(values, rates, accel, DT, cfg)
            assert np.array_equal(path_v[k], values) and np.array_equal(path_r[k], rates)


def test_slew_path_equals_repeated_slew_limit():
    rng = np.random.default_rng(3)
    previous, targets, max_step = rng.normal(size=18), rng.normal(size=(12, 18)), np.full(18, 0.05)
    path = slew_path(previous, targets, max_step)
    for k in range(12):
        previous = slew_limit(previous, targets[k], max_step)
        assert np.array_equal(path[k], previous)


def test_joint_targets_continuous_when_parameters_change_mid_stride():
    cfg = CpgConfig()
    cpg = CPG(cfg, TRIPODS)
    gait = GaitMap(RobotSpec(), 0.2, 0.3)
    targets = [gait.joint_targets(xy) for xy in run(cpg, 0.7, accel=np.asarray(cfg.accel_limit))]
    targets += [gait.joint_targets(xy) for xy in run(cpg, 0.7, accel=-np.asarray(cfg.accel_limit))]
    jumps = np.abs(np.diff(np.array(targets), axis=0)).max()
    # fastest joint motion is omega * a plus the parameter rate, both bounded: no step larger than a few mrad
    assert jumps < 0.05
    assert not np.allclose(cpg.params, cfg.initial)


def test_parameter_integration_respects_bounds_and_rate_limits():
    cfg = CpgConfig()
    values, rates = np.asarray(cfg.initial), np.zeros(3)
    for _ in range(2000):
        values, rates = integrate_parameters(values, rates, np.asarray(cfg.accel_limit), DT, cfg)
        assert np.all(np.abs(rates) <= np.asarray(cfg.rate_limit) + 1e-12)
    assert np.allclose(values, cfg.upper)
    assert np.allclose(rates, 0.0)
    for _ in range(4000):
        values, rates = integrate_parameters(values, rates, -np.asarray(cfg.accel_limit), DT, cfg)
        assert np.all(rates >= -np.asarray(cfg.falling_limit) - 1e-12)
    assert np.allclose(values, cfg.lower)


def test_fall_rate_limit_slows_the_fall_alone():
    cfg = CpgConfig(fall_rate_limit=(1.0, 0.1, 10.0))
    values, rates = np.array([0.25, 0.5, 4.0]), np.zeros(3)
    down = -np.asarray(cfg.accel_limit)
    for _ in range(240):  # one second of full negative acceleration
        values, rates = integrate_parameters(values, rates, down, DT, cfg)
    assert rates[1] == pytest.approx(-0.1)  # b falls at its own 0.1 rad/s: about 0.1 rad in the second
    assert 0.39 < values[1] < 0.41
    assert values[0] == pytest.approx(cfg.lower[0])  # a keeps the symmetric 1 rad/s and reaches its floor
    values, rates = np.array([0.25, 0.2, 4.0]), np.zeros(3)
    for _ in range(60):  # rising is not slowed: 4 rad/s^2 for 0.25 s reaches the 1 rad/s rate limit
        values, rates = integrate_parameters(values, rates, -down, DT, cfg)
    assert rates[1] == pytest.approx(cfg.rate_limit[1])
    assert CpgConfig(fall_rate_limit=None).falling_limit == CpgConfig().rate_limit


def test_a_first_order_command_is_the_rate_at_once_and_zero_holds():
    cfg = CpgConfig(action_order=1, fall_rate_limit=(1.0, 0.1, 10.0))
    start = np.array([0.25, 0.3, 4.0])
    values, rates = parameter_path(start, np.zeros(3), np.array([0.5, 0.5, -2.0]), DT, 24, cfg)
    assert np.allclose(rates, [0.5, 0.5, -2.0])  # no ramp: the first substep already moves at the commanded rate
    assert np.allclose(values[-1], start + 24 * DT * np.array([0.5, 0.5, -2.0]))
    held, held_rates = parameter_path(values[-1], rates[-1], np.zeros(3), DT, 24, cfg)
    assert np.array_equal(held[-1], values[-1]) and np.allclose(held_rates, 0.0)  # a rate that persists is order 2's
    _, falling = parameter_path(values[-1], rates[-1], np.array([0.0, -1.0, 0.0]), DT, 24, cfg)
    assert np.allclose(falling[:, 1], -0.1)  # the fall limit still bounds a commanded fall
    second = CpgConfig(fall_rate_limit=(1.0, 0.1, 10.0))
    _, coasting = parameter_path(values[-1], rates[-1], np.zeros(3), DT, 24, second)
    assert np.allclose(coasting[-1], rates[-1])  # under order 2 the same zero command keeps the rate


def test_holding_widens_only_the_bounds_a_fixed_gait_needs():
    cfg = CpgConfig(lower=(0.05, 0.2, math.pi), initial=(0.25, 0.2, 1.5 * math.pi))  # the floors sweeps' bounds
    held = cfg.holding((0.25, 0.15, 1.5 * math.pi))
    assert held.initial == (0.25, 0.15, 1.5 * math.pi)
    assert held.lower == (cfg.lower[0], 0.15, cfg.lower[2]) and held.upper == cfg.upper
    assert cfg.holding((0.3, 0.4, 4.0)).lower == cfg.lower
    pinned = CpgConfig(lower=(0.4, 0.2, math.pi), upper=(0.4, 0.5, math.pi), initial=(0.4, 0.2, math.pi))
    fast = pinned.holding((0.2, 0.3, 2 * math.pi))  # a grid gait shorter and faster than the pinned default
    assert fast.lower == (0.2, 0.2, math.pi) and fast.upper == (0.4, 0.5, 2 * math.pi)


def test_a_fixed_gait_above_the_ceilings_holds_through_its_episode():
    """The CPG clips to its bounds each step: a gait above cpg.upper would be run as another gait unless `holding`
    raised the ceilings to it (the grid's omega = 2 pi under a default that pins omega at pi)."""
    pinned = CpgConfig(lower=(0.4, 0.2, math.pi), upper=(0.4, 0.5, math.pi), initial=(0.4, 0.2, math.pi))
    gait = np.array([0.3, 0.45, 2 * math.pi])
    held = pinned.holding(tuple(gait))
    path, _ = parameter_path(gait, np.zeros(3), np.zeros(3), DT, 24, held)
    assert np.allclose(path, gait)
    clipped, _ = parameter_path(gait, np.zeros(3), np.zeros(3), DT, 24, pinned)
    assert not np.allclose(clipped[-1], gait)  # without it, omega falls to the pinned pi


def test_swing_lifts_and_stance_holds_the_ik_angles():
    gait = GaitMap(RobotSpec(), 0.2, 0.3)
    xy = np.array([[0.1, 0.2], [0.1, -0.2], [0.0, 0.0], [0.0, 0.1], [-0.1, -0.1], [0.0, -0.05]])
    t = gait.joint_targets(xy).reshape(6, 3)
    assert t[0, 1] == pytest.approx(gait.stance_shoulder + 0.2)
    assert t[1, 1] == pytest.approx(gait.stance_shoulder)
    assert np.allclose(t[:, 2], gait.stance_elbow)
    # left legs (sin > 0) yaw with +x, right legs with -x: both sweep the foot backward for increasing x
    assert t[0, 0] == pytest.approx(0.1) and t[1, 0] == pytest.approx(-0.1)
    # a whole control step maps at once, substep by substep
    steps = np.stack([xy, -xy, 0.5 * xy])
    assert np.array_equal(gait.joint_targets(steps), np.stack([gait.joint_targets(x) for x in steps]))


def test_leg_ik_reaches_target_and_rejects_unreachable():
    s, e = leg_ik(0.25, 0.18, 0.325, 0.325)
    fx = 0.325 * math.cos(s) + 0.325 * math.cos(s + e)
    fz = 0.325 * math.sin(s) + 0.325 * math.sin(s + e)
    assert (fx, fz) == pytest.approx((0.25, -0.18), abs=1e-9)
    assert 0.325 * math.sin(s) > 0  # knee up
    with pytest.raises(ValueError, match="workspace"):
        leg_ik(0.7, 0.2, 0.325, 0.325)
