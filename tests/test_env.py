"""The Gymnasium environment: API checkers, determinism, sensors, termination reasons and the physical premise."""

import math
import warnings

import gymnasium
import numpy as np
import pytest

import hexpipe
from hexpipe.config import CpgConfig, SensorConfig, TaskConfig
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.sensors import SENSORS

LOW_GAIT = (0.25, 0.15, 1.5 * math.pi)  # the default: fast, low steps
HIGH_GAIT = (0.25, 0.40, 1.5 * math.pi)  # b = 0.40 rad lifts the feet ~0.15 m, over the 0.10 m block


def holding(gait):
    """The env's CPG settings for a fixed gait: it holds even where cpg.lower is raised above it."""
    return CpgConfig().holding(gait)


def rollout(env: HexapodEnv, seed: int, actions=None, max_steps: int = 10_000) -> dict:
    env.reset(seed=seed)
    for i in range(max_steps):
        action = np.zeros(3) if actions is None else actions[i % len(actions)]
        _, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            return info | {"truncated": truncated}
    raise AssertionError("episode did not end")


def test_registered_with_gymnasium():
    env = gymnasium.make(hexpipe.ENV_ID, terrain="flat")
    obs, info = env.reset(seed=0)
    assert set(obs) == {"body", "cpg", "heightmap"}
    assert info["distance"] == pytest.approx(0.0, abs=1e-6)
    env.close()


def test_gymnasium_and_sb3_checkers_pass_without_warnings():
    from gymnasium.utils.env_checker import check_env as gym_check
    from stable_baselines3.common.env_checker import check_env as sb3_check

    for sensors in [("heightmap",), ("rgb", "heightmap"), ()]:
        env = HexapodEnv("single_block", task=TaskConfig(sensors=sensors))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            gym_check(env, skip_render_check=True)
            sb3_check(env, warn=True)
        env.close()
        assert not [str(w.message) for w in caught], sensors


def test_same_seed_same_rollout_and_random_terrain_depends_on_seed():
    actions = np.random.default_rng(0).uniform(-1, 1, size=(40, 3))
    runs = []
    for seed in (3, 3, 4):
        env = HexapodEnv("random_blocks")
        obs, _ = env.reset(seed=seed)
        trace = [obs["heightmap"].copy()]
        for a in actions:
            obs, reward, *_ = env.step(a)
            trace.append(np.concatenate([obs["body"], obs["cpg"], [reward]]))
        runs.append(trace)
        env.close()
    assert all(np.array_equal(x, y) for x, y in zip(runs[0], runs[1], strict=True))
    assert not np.array_equal(runs[0][0], runs[2][0])  # another seed, other blocks


def test_actions_steer_cpg_parameters_within_bounds():
    env = HexapodEnv("flat")
    env.reset(seed=0)
    for _ in range(40):
        _, _, _, _, info = env.step(np.array([1.0, 1.0, -1.0]))
    a, b, omega = info["cpg"]
    assert a == pytest.approx(env.cpg_cfg.upper[0]) and b == pytest.approx(env.cpg_cfg.upper[1])
    assert omega == pytest.approx(env.cpg_cfg.lower[2])
    env.close()


def test_heightmap_sees_the_block_and_camera_renders_it():
    env = HexapodEnv("single_block", task=TaskConfig(sensors=("rgb", "heightmap")))
    obs, _ = env.reset(seed=0)
    hm = obs["heightmap"].reshape(SENSORS["heightmap"].frame_shape(env.sensor_cfg))
    near, far = env.sensor_cfg.heightmap_ahead
    row_x = near + (np.arange(hm.shape[0]) + 0.5) * (far - near) / hm.shape[0]
    on_block = (row_x > 1.03) & (row_x < 1.27)
    assert np.allclose(hm[on_block], 0.10, atol=0.02)
    assert np.allclose(hm[row_x < 0.9], 0.0, atol=0.02)
    rgb = obs["rgb"]
    assert rgb.shape == (64, 64, 3) and rgb.dtype == np.uint8 and rgb.std() > 5
    env.close()


def test_heightmap_reaches_behind_the_hind_feet():
    """A hind foot stalls at a face the body has long passed (on the wide block, the policy made with the old map
    stopped with the base 0.47-0.49 m past the face): the map must reach behind every foot, and show that face."""
    env = HexapodEnv("flat")
    env.reset(seed=0)
    behind = []
    for _ in range(40):
        env.step(np.zeros(3))
        base = env.robot.base_state()[0]
        behind += [c[5][0] - base[0] for c in env._p.getContactPoints(bodyA=env.robot.body)]
    env.close()
    near, _ = SensorConfig().heightmap_ahead
    assert near < min(behind) < -0.4  # the hind feet touch down ~0.5 m behind the base; the map starts behind that

    single_block = HexapodEnv("single_block")
    single_block.reset(seed=0)
    sensor = SENSORS["heightmap"].reader(single_block.sensor_cfg)
    hm = sensor.read(single_block.terrain, np.array([1.48, 0.0]), yaw=0.0, plane_z=0.0)  # base 0.48 m past the face
    single_block.close()
    row_x = near + (np.arange(hm.shape[0]) + 0.5) * sensor.cell_x
    assert np.allclose(hm[(row_x > -0.44) & (row_x < -0.22)], 0.10)  # the block under the hind legs
    assert np.allclose(hm[row_x < -0.5], 0.0)  # and the ground before its face, where a hind foot stands


def test_a_ground_referenced_map_reads_a_block_at_its_height_wherever_the_body_stands():
    """Between the extra blocks, with the hind legs on the first, the body stands high and the stance-plane map
    reads the 0.10 m second block lower (reports/experiments/sde/map_reference.py); from the ground under the base
    it reads 0.10. Over the first block, the ground reference reads the second block level and the gap as a dip."""
    from hexpipe.sensors.base import SimView
    from hexpipe.sim.terrain import SCENARIOS, realize

    terrain = realize(SCENARIOS["extra_blocks"], np.random.default_rng(0))
    ahead = {ref: SENSORS["heightmap"].reader(SensorConfig(heightmap_reference=ref)) for ref in ("stance", "ground")}
    near, _ = SensorConfig().heightmap_ahead
    sensor = ahead["stance"]
    row_x = near + (np.arange(sensor.shape[0]) + 0.5) * sensor.cell_x
    level = np.array([0.0, 0.0, 0.0, 1.0])

    def read(ref: str, x: float, z: float) -> np.ndarray:
        return ahead[ref](SimView(0, None, terrain, np.array([x, 0.0, z]), level, 0.24))[:, 16]

    raised = 0.24 + 0.05  # base 1.5 m out, between the blocks, held 5 cm above its nominal height
    second = (row_x > 0.55) & (row_x < 0.75)  # the second block's top: 2.05-2.25 m
    np.testing.assert_allclose(read("stance", 1.5, raised)[second], 0.05, atol=1e-6)
    np.testing.assert_allclose(read("ground", 1.5, raised)[second], 0.10, atol=1e-6)
    over_first = read("ground", 1.15, 0.10 + 0.20)  # base over the first block, whatever its height above it
    np.testing.assert_allclose(over_first[(row_x > 0.95) & (row_x < 1.1)], 0.0, atol=1e-6)  # the second: level
    np.testing.assert_allclose(over_first[(row_x > 0.25) & (row_x < 0.75)], -0.10, atol=1e-6)  # the gap: a dip

    frames = {}
    for ref in ("stance", "ground"):  # the map's frame in the log, where Foxglove draws its cells
        env = HexapodEnv("extra_blocks", sensors=SensorConfig(heightmap_reference=ref))
        env.reset(seed=0)
        frames[ref] = next(t for t in env.state().transforms if t[1] == "heading")[2][2]
        env.close()
    assert frames["ground"] == 0.0 and frames["stance"] != 0.0  # on the ground under the base, or the stance plane


def test_truncates_at_time_limit():
    env = HexapodEnv("flat", task=TaskConfig(time_limit=1.0))
    info = rollout(env, seed=0)
    assert info["truncated"] and info["termination"] is None and not info["success"]
    env.close()


@pytest.mark.parametrize(("fall_height", "ends"), [(0.07, "fall"), (0.04, None)])
def test_fall_height_is_measured_from_the_terrain_under_the_base(fall_height, ends):
    """The base 0.066 m over the tall block's top (0.12 m), as elev_free's straddling dips were (reports/experiments,
    tall_fall): a fall at the default 0.07 m, not at the chassis's half-thickness."""
    env = HexapodEnv("tall_block", task=TaskConfig(fall_height=fall_height))
    env.reset(seed=0)
    over_block = np.array([env.start_xy[0] + 1.15, env.start_xy[1], 0.12 + 0.066])
    assert env._termination(over_block, np.array([0.0, 0.0, 0.0, 1.0])) == ends
    env.close()


def test_flipped_robot_is_a_fall():
    env = HexapodEnv("flat")
    env.reset(seed=0)
    env._p.resetBasePositionAndOrientation(env.robot.body, [0, 0, 0.3], [1, 0, 0, 0], physicsClientId=env.client)
    _, _, terminated, _, info = env.step(np.zeros(3))
    assert terminated and info["termination"] == "fall"
    env.close()


def test_nonfinite_physics_terminates_without_crash(monkeypatch):
    env = HexapodEnv("flat")
    env.reset(seed=0)
    nan = np.full(3, np.nan)
    monkeypatch.setattr(env.robot, "base_state", lambda: (nan, np.full(4, np.nan), nan, nan))
    obs, reward, terminated, _, info = env.step(np.zeros(3))
    assert terminated and info["termination"] == "nonfinite" and np.isfinite(reward)
    assert all(np.all(np.isfinite(v)) for v in obs.values())
    env.close()


def test_initial_cpg_outside_bounds_is_rejected():
    with pytest.raises(ValueError, match="initial_cpg"):
        HexapodEnv("flat", initial_cpg=(0.25, 0.9, 4.0))


# -- the physical premise: the gait walks, the block stops a low gait, a high gait clears it ----------------------
@pytest.mark.parametrize("seed", [0, 1])
def test_default_gait_walks_3m_on_flat(seed):
    env = HexapodEnv("flat", task=TaskConfig(sensors=()))
    info = rollout(env, seed)
    assert info["termination"] == "goal" and info["success"]
    assert info["time"] < 20.0  # >= 0.15 m/s
    env.close()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_block_stops_the_low_gait(seed):
    env = HexapodEnv("single_block", cpg=holding(LOW_GAIT), initial_cpg=LOW_GAIT, task=TaskConfig(sensors=()))
    info = rollout(env, seed)
    assert info["termination"] == "stuck"
    assert 0.3 < info["distance"] < 0.7  # front feet against the block face at 1.0 m
    env.close()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_high_gait_clears_the_block(seed):
    env = HexapodEnv("single_block", initial_cpg=HIGH_GAIT, task=TaskConfig(sensors=()))
    info = rollout(env, seed)
    assert info["termination"] == "goal"
    env.close()


def test_sensor_config_shapes_observation():
    env = HexapodEnv(
        "flat", sensors=SensorConfig(camera_width=48, camera_height=32, heightmap_rows=16, heightmap_cols=8),
        task=TaskConfig(sensors=("rgb", "heightmap")),
    )
    obs, _ = env.reset(seed=0)
    assert obs["rgb"].shape == (32, 48, 3) and obs["heightmap"].shape == (16 * 8,)
    env.close()


# -- the reward: the paper's term, and the optional power cost ---------------------------------------------------
def test_reward_is_the_papers_unless_power_costs_something():
    rewards = {}
    for cost in (0.0, 0.1):
        env = HexapodEnv("flat", task=TaskConfig(sensors=(), power_cost=cost))
        env.reset(seed=0)
        for _ in range(30):
            _, reward, _, _, info = env.step(np.zeros(3))
        terms = info["reward_terms"]
        assert reward == pytest.approx(sum(terms.values()))
        assert info["power"] > 1.0 and info["energy"] > 0.0  # the legs do work while walking
        assert terms["power"] == pytest.approx(-cost * info["power"])
        rewards[cost] = (reward, terms["forward"])
        env.close()
    assert rewards[0.0][0] == pytest.approx(rewards[0.0][1])  # 100 * v_x alone
    assert rewards[0.1][0] < rewards[0.1][1]


def test_the_lift_price_charges_b_above_its_floor_and_nothing_at_the_floor():
    """task.lift_cost prices the commanded lift, per rad above cpg.lower's b, each step; the floor walks free."""
    charged = {}
    for gait in (HIGH_GAIT, (0.25, 0.2, 1.5 * math.pi)):
        env = HexapodEnv("flat", cpg=holding(gait), initial_cpg=gait, task=TaskConfig(sensors=(), lift_cost=10.0))
        env.reset(seed=0)
        for _ in range(5):
            _, reward, _, _, info = env.step(np.zeros(3))
        assert reward == pytest.approx(sum(info["reward_terms"].values()))
        charged[gait[1]] = info["reward_terms"]["lift"]
        env.close()
    assert charged[0.40] == pytest.approx(-10.0 * (0.40 - 0.2)) and charged[0.2] == 0.0


def test_a_lift_free_zone_waives_the_lift_price_near_the_block_and_charges_it_on_level_ground():
    """task.lift_free_zone: the high gait pays for its lift until the block's face is 0.5 m ahead, then walks free
    until its back edge is 0.4 m behind."""
    task = TaskConfig(sensors=(), lift_cost=10.0, lift_free_zone=(0.4, 0.5))
    env = HexapodEnv("single_block", cpg=holding(HIGH_GAIT), initial_cpg=HIGH_GAIT, task=task)
    env.reset(seed=0)
    lift_by_x = []
    for _ in range(2000):
        _, reward, terminated, truncated, info = env.step(np.zeros(3))
        assert reward == pytest.approx(sum(info["reward_terms"].values()))
        lift_by_x.append((float(env.robot.base_state()[0][0]), info["reward_terms"]["lift"]))
        if terminated or truncated or lift_by_x[-1][0] > 2.0:
            break
    env.close()
    charged = -10.0 * (HIGH_GAIT[1] - 0.2)
    assert lift_by_x[-1][0] > 2.0  # the high gait crossed
    before, near, after = ([lift for x, lift in lift_by_x if lo < x < hi] for lo, hi in ((0, 0.45), (0.55, 1.65),
                                                                                          (1.75, 9)))
    assert before and near and after
    assert before == pytest.approx([charged] * len(before)) and after == pytest.approx([charged] * len(after))
    assert near == [0.0] * len(near)


def test_a_lift_price_zone_charges_the_lift_sooner_past_the_block_and_leaves_the_rest_as_lift_free_zone():
    """task.lift_price_zone moves only the price's waiver: with 0.1 m behind instead of 0.6, the high gait pays
    again once the block's back edge (1.3 m) is 0.1 m behind, not 0.6 m; before the block both waive alike."""
    lift_by_x = {}
    for price_zone in (None, (0.1, 0.7)):
        task = TaskConfig(sensors=(), lift_cost=10.0, lift_free_zone=(0.6, 0.7), lift_price_zone=price_zone)
        env = HexapodEnv("single_block", cpg=holding(HIGH_GAIT), initial_cpg=HIGH_GAIT, task=task)
        env.reset(seed=0)
        rows = []
        for _ in range(2000):
            _, _, terminated, truncated, info = env.step(np.zeros(3))
            rows.append((float(env.robot.base_state()[0][0]), info["reward_terms"]["lift"]))
            if terminated or truncated or rows[-1][0] > 2.1:
                break
        env.close()
        lift_by_x[price_zone] = rows
    charged = -10.0 * (HIGH_GAIT[1] - 0.2)
    default, near = lift_by_x[None], lift_by_x[(0.1, 0.7)]
    assert [x for x, _ in default] == [x for x, _ in near]  # the price moves no leg: the same walk
    for rows in (default, near):
        assert all(lift == 0.0 for x, lift in rows if 0.45 < x < 1.35)
    past = [(x, a, b) for (x, a), (_, b) in zip(default, near, strict=True) if 1.5 < x < 1.85]
    assert past and all(a == 0.0 and b == pytest.approx(charged) for _, a, b in past)


def test_the_lift_free_zone_asks_the_terrain_nothing_while_the_lift_price_is_ramped_to_zero(monkeypatch):
    """ppo.lift_cost_ramp holds the price's share at 0 for the first part of training: the zone's check (30 us a
    step, benchmarks/bench_lift_free.py) is skipped there, and only there."""
    task = TaskConfig(sensors=(), lift_cost=10.0, lift_free_zone=(0.6, 0.7))
    env = HexapodEnv("single_block", cpg=holding(HIGH_GAIT), initial_cpg=HIGH_GAIT, task=task)
    env.reset(seed=0)
    asked = []
    monkeypatch.setattr(env.terrain.__class__, "relief", lambda self, *args: asked.append(args) or 0.0)
    env.set_lift_cost_share(0.0)
    env.step(np.zeros(3))
    assert asked == []
    env.set_lift_cost_share(0.5)
    _, _, _, _, info = env.step(np.zeros(3))
    env.close()
    assert len(asked) == 1 and info["reward_terms"]["lift"] == pytest.approx(-0.5 * 10.0 * (HIGH_GAIT[1] - 0.2))


def test_giving_up_costs_the_failure_penalty_once_and_reaching_the_goal_costs_nothing():
    ends = {}
    for terrain, gait in (("single_block", LOW_GAIT), ("flat", None)):  # the low gait sticks at the block face
        cpg = holding(gait) if gait else None
        env = HexapodEnv(terrain, cpg=cpg, initial_cpg=gait, task=TaskConfig(sensors=(), failure_penalty=500.0))
        env.reset(seed=0)
        failure, done = [], False
        while not done:
            _, reward, terminated, truncated, info = env.step(np.zeros(3))
            failure.append(info["reward_terms"]["failure"])
            done = terminated or truncated
        assert reward == pytest.approx(sum(info["reward_terms"].values()))
        ends[terrain] = (info["termination"], failure[-1], any(failure[:-1]))
        env.close()
    assert ends == {"single_block": ("stuck", -500.0, False), "flat": ("goal", 0.0, False)}


def test_a_high_gait_costs_more_energy_per_metre_on_flat():
    """Why the power cost makes lifting a choice: on open ground the high gait only spends more."""
    from hexpipe.envs.rewards import cost_of_transport

    cot = {}
    for gait in (LOW_GAIT, HIGH_GAIT):
        env = HexapodEnv("flat", cpg=holding(gait), initial_cpg=gait, task=TaskConfig(sensors=(), time_limit=8.0))
        info = rollout(env, seed=0)
        cot[gait] = cost_of_transport(info["energy"], env.robot_spec.total_mass, info["distance"])
        env.close()
    assert cot[HIGH_GAIT] > 1.2 * cot[LOW_GAIT]
