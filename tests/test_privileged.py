"""The privileged critic (ppo.privileged_critic): what only the critic sees, and that the actor never sees it."""

import numpy as np
import pytest
import torch
from gymnasium import spaces
from gymnasium.utils.env_checker import check_env
from stable_baselines3.common.policies import ActorCriticPolicy

from hexpipe.config import Params, SensorConfig
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.envs.privileged import PRIVILEGED, corridor_columns, privileged_size, privileged_vector
from hexpipe.rl.asymmetric import AsymmetricPolicy, actor_only


def test_the_profile_is_the_highest_terrain_in_each_row_across_the_legs_corridor():
    cfg = SensorConfig()
    grid = np.zeros((cfg.heightmap_rows, cfg.heightmap_cols), dtype=np.float32)
    inside = np.flatnonzero(corridor_columns(cfg))
    grid[20:, inside[0]] = 0.1  # a block edge within the corridor
    grid[:, 0] = 0.5  # a wall far to the side: outside the corridor, not under the legs
    vector = privileged_vector(grid.ravel(), friction=0.7, mass_scale=1.1, sensors=cfg)
    assert vector.shape == (privileged_size(cfg),) and vector.dtype == np.float32
    np.testing.assert_allclose(vector[:20], 0.0)
    np.testing.assert_allclose(vector[20 : cfg.heightmap_rows], 0.1)
    np.testing.assert_allclose(vector[-2:], [0.7, 1.1], rtol=1e-6)
    assert not corridor_columns(cfg)[0] and corridor_columns(cfg).sum() == 16  # |y| <= 0.4 m of a 1.6 m map


def test_a_coarse_map_with_no_column_in_the_corridor_uses_every_column():
    cfg = SensorConfig(heightmap_cols=2, heightmap_width=2.0)  # column centres at +-0.5 m
    assert corridor_columns(cfg).all()


def test_the_env_shows_the_critic_the_block_where_it_is_and_the_physics_it_drew():
    params = Params()
    env = HexapodEnv.from_params(params, "single_block", obs_sensors=(), privileged=True, randomize=True)
    obs, _ = env.reset(seed=3)
    assert set(obs) == {"body", "cpg", PRIVILEGED}  # no sensor observed: the profile is read for the critic alone
    vector = obs[PRIVILEGED]
    near, far = params.sensors.heightmap_ahead
    rows = near + (far - near) / params.sensors.heightmap_rows * (np.arange(params.sensors.heightmap_rows) + 0.5)
    profile = vector[: len(rows)]
    on_block = (rows > 1.02) & (rows < 1.28)  # single_block: 0.1 m high, from 1.0 to 1.3 m ahead of the start
    assert np.all(profile[on_block] > 0.07) and np.all(np.abs(profile[(rows < 0.95) | (rows > 1.35)]) < 0.03)
    friction, mass_scale = vector[-2:]
    rnd = params.task.randomization
    assert rnd.friction[0] <= friction <= rnd.friction[1] and rnd.mass_scale[0] <= mass_scale <= rnd.mass_scale[1]
    env.close()
    check_env(HexapodEnv.from_params(params, "single_block", obs_sensors=("heightmap",), privileged=True),
              skip_render_check=True)


def test_without_the_setting_the_observation_is_unchanged():
    env = HexapodEnv.from_params(Params(), "single_block", obs_sensors=("heightmap",))
    obs, _ = env.reset(seed=0)
    assert set(obs) == {"body", "cpg", "heightmap"}
    env.close()


def policy(actor_dim: int = 5, total: int = 9) -> AsymmetricPolicy:
    torch.manual_seed(0)
    space = spaces.Box(-np.inf, np.inf, shape=(total,), dtype=np.float32)
    return AsymmetricPolicy(space, spaces.Box(-1, 1, (3,)), lr_schedule=lambda _: 3e-4, net_arch=[16, 16],
                            actor_dim=actor_dim)


def test_the_actor_never_reads_the_privileged_features_and_the_critic_does():
    net = policy()
    x = torch.randn(4, 9)
    moved = x.clone()
    moved[:, 5:] += 3.0  # only the privileged part changes
    with torch.no_grad():
        same_actions = torch.equal(net.get_distribution(x).distribution.mean,
                                   net.get_distribution(moved).distribution.mean)
        values_move = not torch.allclose(net.predict_values(x), net.predict_values(moved))
    assert same_actions and values_move
    assert net.mlp_extractor.policy_net[0].in_features == 5 and net.mlp_extractor.value_net[0].in_features == 9
    with pytest.raises(ValueError, match="actor_dim=10"):
        policy(actor_dim=10)


def test_the_exported_actor_acts_as_the_trained_one_and_carries_no_critic():
    net = policy()
    plain = actor_only(net)
    assert type(plain) is ActorCriticPolicy and plain.observation_space.shape == (5,)
    x = np.random.default_rng(0).normal(size=(6, 9)).astype(np.float32)
    np.testing.assert_array_equal(net.predict(x, deterministic=True)[0], plain.predict(x[:, :5], deterministic=True)[0])
    assert all(not v.any() for k, v in plain.state_dict().items() if "value_net" in k)
