"""The numpy rollout forward (hexpipe/rl/rollout.py): the same network and Gaussian as SB3's torch forward, used only
while collecting, refreshed after every update, and deterministic end to end."""

import hashlib

import numpy as np
import torch
from gymnasium import spaces
from test_ppo import tiny

from hexpipe.rl.asymmetric import NumpyAsymmetricPolicy
from hexpipe.rl.rollout import RolloutPolicy
from hexpipe.rl.train import train_ppo


def make(cls=RolloutPolicy, dim: int = 25, **kwargs):
    torch.manual_seed(0)
    space = spaces.Box(-np.inf, np.inf, shape=(dim,), dtype=np.float32)
    policy = cls(space, spaces.Box(-1, 1, (3,)), lr_schedule=lambda _: 3e-4, net_arch=[64, 64], **kwargs)
    with torch.no_grad():
        policy.log_std.fill_(-0.5)
    return policy


def torch_reference(policy, x: torch.Tensor):
    """SB3's own distribution and value for x (grad on: the numpy path stands aside)."""
    dist = policy.get_distribution(x)
    return dist, policy.predict_values(x)


def test_numpy_forward_is_sb3s_network_and_gaussian():
    policy = make()
    policy.set_training_mode(False)  # as collect_rollouts does: takes the snapshot
    x = torch.randn(5, 25)
    with torch.no_grad():
        mean, values, log_prob_mean = policy(x, deterministic=True)
        actions, _, log_prob = policy(x)
    dist, expected_values = torch_reference(policy, x)
    torch.testing.assert_close(mean, dist.distribution.mean.detach(), rtol=1e-5, atol=1e-6)
    torch.testing.assert_close(values, expected_values.detach(), rtol=1e-5, atol=1e-6)
    torch.testing.assert_close(log_prob_mean, dist.log_prob(mean).detach(), rtol=1e-5, atol=1e-5)
    torch.testing.assert_close(log_prob, dist.log_prob(actions).detach(), rtol=1e-5, atol=1e-5)
    assert actions.dtype == values.dtype == log_prob.dtype == torch.float32 and actions.shape == (5, 3)


def test_samples_follow_the_policys_mean_and_spread():
    policy = make()
    policy.set_training_mode(False)
    x = torch.randn(1, 25).repeat(20000, 1)
    with torch.no_grad():
        actions, _, _ = policy(x)
    mean = policy.get_distribution(x[:1]).distribution.mean.detach().numpy()[0]
    np.testing.assert_allclose(actions.numpy().mean(axis=0), mean, atol=0.02)
    np.testing.assert_allclose(actions.numpy().std(axis=0), np.exp(-0.5), rtol=0.03)


def test_training_mode_and_gradients_use_torch_and_an_update_refreshes_the_copy():
    policy = make()
    x = torch.randn(3, 25)
    policy.set_training_mode(True)
    with torch.no_grad():
        assert policy._snapshot is None  # training mode: SB3's forward
    _, values, _ = policy(x)
    assert values.grad_fn is not None  # gradients on: SB3's forward
    with torch.no_grad():
        policy.value_net.bias.add_(1.0)  # what an optimiser step does to the weights
    policy.set_training_mode(False)  # the next rollout
    with torch.no_grad():
        _, fresh, _ = policy(x, deterministic=True)
    torch.testing.assert_close(fresh, policy.predict_values(x).detach(), rtol=1e-5, atol=1e-6)


def test_the_asymmetric_actor_ignores_privileged_features_in_numpy_too():
    policy = make(NumpyAsymmetricPolicy, dim=30, actor_dim=25)
    policy.set_training_mode(False)
    x = torch.randn(4, 30)
    moved = x.clone()
    moved[:, 25:] += 5.0
    with torch.no_grad():
        a, v, _ = policy(x, deterministic=True)
        b, w, _ = policy(moved, deterministic=True)
    torch.testing.assert_close(a, b)
    assert not torch.allclose(v, w)
    torch.testing.assert_close(a, policy.get_distribution(x).distribution.mean.detach(), rtol=1e-5, atol=1e-6)


def weights_digest(path) -> str:
    state = torch.load(path / "ppo" / "policy" / "weights.pt", weights_only=True)
    return hashlib.sha256(b"".join(v.numpy().tobytes() for v in state.values())).hexdigest()


def test_training_is_deterministic_for_a_seed_and_differs_across_seeds(tmp_path):
    runs = {}
    for name, seed in (("a", 0), ("b", 0), ("c", 1)):
        numpy_forward = ("ppo.blind=true", "ppo.n_envs=2", "ppo.rollout_forward=numpy")
        params = tiny(tmp_path / name, *numpy_forward, f"ppo.seed={seed}")
        train_ppo(params, show_progress=False)
        runs[name] = weights_digest(tmp_path / name)
    assert runs["a"] == runs["b"] != runs["c"]


def test_the_setting_picks_the_policy_class():
    from stable_baselines3.common.policies import ActorCriticPolicy

    from hexpipe.rl.asymmetric import AsymmetricPolicy
    from hexpipe.rl.train import policy_class

    assert policy_class(False, False) is ActorCriticPolicy and policy_class(False, True) is RolloutPolicy
    assert policy_class(True, False) is AsymmetricPolicy and policy_class(True, True) is NumpyAsymmetricPolicy
