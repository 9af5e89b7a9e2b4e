"""The observation without shortcuts: with `task.observe_position=false` the policy sees the same thing at the same
distance from a block wherever the course puts it; with the paper's observation (position kept) it does not."""

import warnings
from pathlib import Path

import numpy as np
import pytest

from hexpipe.config import TaskConfig
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.sim.terrain import BlockSpec, TerrainRecipe

ROOT = Path(__file__).resolve().parents[1]

SHIFT = 0.4  # m the whole course moves along x


def course(face: float) -> TerrainRecipe:
    return TerrainRecipe(name=f"block_at_{face}", boxes=(BlockSpec(face=face, depth=0.3, height=0.1),))


def observations(face: float, walked: float, observe_position: bool, steps: int = 4) -> list[dict[str, np.ndarray]]:
    """Reset on a block at `face`, put the robot `walked` m along x (its start stays at the origin, as if it had
    walked there), then step a few fixed actions; the observation after each."""
    env = HexapodEnv(course(face), task=TaskConfig(observe_position=observe_position))
    try:
        env.reset(seed=0)
        p = env._p
        pos, quat, _, _ = env.robot.base_state()
        p.resetBasePositionAndOrientation(
            env.robot.body, (pos + np.array([walked, 0.0, 0.0])).tolist(), quat.tolist(), physicsClientId=env.client
        )
        out = [env._observation()]
        for action in np.random.default_rng(0).uniform(-1, 1, size=(steps, 3)):
            obs, *_ = env.step(action)
            out.append(obs)
        return out
    finally:
        env.close()


@pytest.mark.parametrize("observe_position", [True, False])
def test_shifted_course_looks_the_same_only_without_position(observe_position: bool) -> None:
    # Same distance (1.0 m) to the block's face: at the start of the paper's course, and 0.4 m into the shifted one.
    here = observations(face=1.0, walked=0.0, observe_position=observe_position)
    shifted = observations(face=1.0 + SHIFT, walked=SHIFT, observe_position=observe_position)
    for a, b in zip(here, shifted, strict=True):
        assert a.keys() == b.keys() == {"body", "cpg", "heightmap"}
        np.testing.assert_array_equal(a["cpg"], b["cpg"])
        np.testing.assert_allclose(a["heightmap"], b["heightmap"], atol=1e-5)  # the block 1.0 m ahead in both
        if observe_position:  # x relative to the start gives the layout away
            assert b["body"][0] - a["body"][0] == pytest.approx(SHIFT, abs=0.01)
            np.testing.assert_allclose(a["body"][1:], b["body"][1:], atol=1e-3)
        else:
            assert a["body"].shape == (11,)
            np.testing.assert_allclose(a["body"], b["body"], atol=1e-3)  # physics is translation-invariant to ~1e-4


def test_observation_space_follows_the_setting_and_checkers_pass() -> None:
    from gymnasium.utils.env_checker import check_env as gym_check
    from stable_baselines3.common.env_checker import check_env as sb3_check

    for observe_position, size in ((True, 13), (False, 11)):
        env = HexapodEnv("single_block", task=TaskConfig(observe_position=observe_position))
        assert env.observation_space["body"].shape == (size,)
        obs, _ = env.reset(seed=1)
        assert obs["body"].shape == (size,)
        assert env._zero_observation()["body"].shape == (size,)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            gym_check(env, skip_render_check=True)
            sb3_check(env, warn=True)
        env.close()
        assert not [str(w.message) for w in caught]


def test_cpg_rates_are_bounded_by_the_fall_rate_limit() -> None:
    from hexpipe.config import CpgConfig, SensorConfig
    from hexpipe.envs.hexapod import observation_space

    space = observation_space(CpgConfig(fall_rate_limit=(1.0, 0.1, 10.0)), SensorConfig(), TaskConfig())["cpg"]
    np.testing.assert_allclose(space.low[3:], [-1.0, -0.1, -10.0])
    np.testing.assert_allclose(space.high[3:], CpgConfig().rate_limit)


def test_policy_features_follow_the_setting() -> None:
    """The VecEnv feature wrapper sizes its vector from the env's spaces: 2 fewer inputs without position."""
    from stable_baselines3.common.vec_env import DummyVecEnv

    from hexpipe.rl.features import TerrainFeatures

    dims = {}
    for observe_position in (True, False):
        task = TaskConfig(observe_position=observe_position, sensors=())
        venv = DummyVecEnv([lambda task=task: HexapodEnv("flat", task=task)])
        wrapped = TerrainFeatures(venv, expect_embedding=False)
        dims[observe_position] = wrapped.observation_space.shape[0]
        assert wrapped.reset().shape == (1, dims[observe_position])
        wrapped.close()
    assert dims == {True: 19, False: 17}


def tiny_training(tmp_path: Path) -> list[str]:
    """Overrides for a blind PPO run of 64 steps into tmp_path: enough to write a loadable policy."""
    return [
        "ppo.total_timesteps=64", "ppo.n_steps=64", "ppo.batch_size=64", "ppo.n_epochs=1", "ppo.n_envs=1",
        "ppo.blind=true", "ppo.train_terrains=[single_block]", "task.time_limit=2.0",
        f"ppo.out_dir={tmp_path / 'ppo'}", f"ppo.report_dir={tmp_path / 'reports'}",
    ]


def test_a_policy_trained_without_position_loads_only_with_that_setting(tmp_path) -> None:
    from hexpipe.config import load_params
    from hexpipe.rl.policy import PolicyError, load_policy
    from hexpipe.rl.train import train_ppo

    tiny = tiny_training(tmp_path)
    params = load_params(ROOT / "params.yaml", [*tiny, "task.observe_position=false"])
    train_ppo(params, show_progress=False)
    policy = load_policy(tmp_path / "ppo", params)
    assert policy.config["observation_dim"] == 17 and policy.config["observe_position"] is False
    env = HexapodEnv("single_block", task=params.task.model_copy(update={"sensors": ()}))
    obs, _ = env.reset(seed=0)
    assert policy.predict(obs).shape == (3,)
    env.close()
    paper = load_params(ROOT / "params.yaml", [*tiny, "task.observe_position=true"])
    with pytest.raises(PolicyError, match=r"task\.observe_position=false, params now have true"):
        load_policy(tmp_path / "ppo", paper)


def test_the_phase_setting_adds_the_legs_phase_to_the_cpg_observation() -> None:
    """With task.observe_phase the `cpg` entry ends with (cos, sin) of leg 0's oscillator, which turns at omega."""
    from gymnasium.utils.env_checker import check_env as gym_check

    plain = HexapodEnv("flat", task=TaskConfig(sensors=()))
    assert plain.observation_space["cpg"].shape == (6,)
    plain.close()
    env = HexapodEnv("flat", task=TaskConfig(sensors=(), observe_phase=True))
    assert env.observation_space["cpg"].shape == (8,)
    obs, _ = env.reset(seed=3)
    angles = []
    for _ in range(5):
        cos, sin = obs["cpg"][6:]
        assert cos == pytest.approx(np.cos(np.angle(env.cpg.w[0])), abs=1e-6)
        assert sin == pytest.approx(np.sin(np.angle(env.cpg.w[0])), abs=1e-6)
        angles.append(np.arctan2(sin, cos))
        obs, *_ = env.step(np.zeros(3))
    turned = np.mod(np.diff(angles), 2 * np.pi)  # the held gait turns by omega * control_dt each step
    np.testing.assert_allclose(turned, env.cpg.params[2] * env.control_dt, rtol=0.05)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gym_check(env, skip_render_check=True)
    env.close()
    assert not [str(w.message) for w in caught]


def test_a_policy_trained_with_the_phase_loads_with_it_and_is_refused_without(tmp_path) -> None:
    from hexpipe.config import load_params
    from hexpipe.rl.policy import PolicyError, load_policy
    from hexpipe.rl.train import train_ppo

    tiny = tiny_training(tmp_path)
    train_ppo(load_params(ROOT / "params.yaml", [*tiny, "task.observe_phase=true"]), show_progress=False)
    policy = load_policy(tmp_path / "ppo")  # no params: policy.json's own observation settings
    assert policy.config["observation_dim"] == 19 and policy.params.task.observe_phase
    env = HexapodEnv("flat", **policy.env_kwargs)
    obs, _ = env.reset(seed=0)
    assert obs["cpg"].shape == (8,) and policy.predict(obs).shape == (3,)
    env.close()
    with pytest.raises(PolicyError, match=r"task\.observe_phase=true, params now have false") as exc:
        load_policy(tmp_path / "ppo", load_params(ROOT / "params.yaml", tiny))
    assert "\n" not in str(exc.value)
