"""The policy's forward pass while PPO collects a rollout, in numpy: the same network and the same Gaussian, at a
fraction of torch's per-call cost.

On 2 cores with 2 envs, SB3's PPO waits for the envs, then for the policy, then for the envs again: nothing
overlaps, so every microsecond of the forward pass is lost env time. For a batch of 2 and two 64-wide layers,
torch's eager forward is about 20 operator calls plus a distribution object and its checks; the same arithmetic in
numpy costs a fraction of that (`hexpipe bench`: `training.forward_us`, and training's rate with each forward).

Only the rollout changes. While the policy is in eval mode and no gradient is taken, `forward` runs the copy of the
weights taken when SB3 switched to eval mode (at the start of every rollout, after the last update); the PPO
update, `predict` and value bootstrapping stay torch. Actions are drawn from the same N(mean, exp(log_std)) from a
numpy generator seeded from torch's, so a run is as deterministic as before, though not bit-identical to a run
with torch's forward (other random draws, other rounding).

The default (`ppo.rollout_forward: numpy`; `torch` gives SB3's own): over 6 training seeds each it trained
policies as good as the torch forward's (reports/experiments/README.md, "rollout_forward").
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch as th
from stable_baselines3.common.distributions import DiagGaussianDistribution
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.torch_layers import FlattenExtractor

HALF_LOG_2PI = 0.5 * np.log(2 * np.pi)
ACTIVATIONS: dict[type[th.nn.Module], Callable[[np.ndarray], np.ndarray]] = {
    th.nn.Tanh: np.tanh,
    th.nn.ReLU: lambda x: np.maximum(x, 0),
}

Layers = list[tuple[np.ndarray, np.ndarray, Callable[[np.ndarray], np.ndarray] | None]]


def mlp(x: np.ndarray, layers: Layers) -> np.ndarray:
    """x @ W + b through each (W (in, out), b, activation or None) in turn."""
    for weight, bias, activation in layers:
        x = x @ weight + bias
        if activation is not None:
            x = activation(x)
    return x


def gaussian_sample(mean: np.ndarray, log_std: np.ndarray, rng: np.random.Generator,
                    deterministic: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(actions, log-probability summed over action dims) of N(mean, exp(log_std)): SB3's DiagGaussian."""
    noise = np.zeros_like(mean) if deterministic else rng.standard_normal(mean.shape, dtype=np.float32)
    actions = mean + np.exp(log_std) * noise
    log_prob = (-0.5 * noise**2 - log_std - HALF_LOG_2PI).sum(axis=1)
    return actions.astype(np.float32), log_prob.astype(np.float32)


@dataclass
class Snapshot:
    """The weights as numpy, taken when the policy entered eval mode."""

    actor: Layers  # policy net, then action head (no activation)
    critic: Layers  # value net, then value head
    log_std: np.ndarray
    actor_dim: int | None  # the actor reads the leading actor_dim features (an asymmetric policy); None: all


def sequential_layers(module: th.nn.Module) -> Layers | None:
    """An nn.Sequential of Linear layers and known activations (or one Linear) as numpy; None if anything else."""
    children = list(module) if isinstance(module, th.nn.Sequential) else [module]
    layers: Layers = []
    for child in children:
        if isinstance(child, th.nn.Linear):
            layers.append((child.weight.detach().numpy().T.copy(), child.bias.detach().numpy().copy(), None))
        elif type(child) in ACTIVATIONS and layers and layers[-1][2] is None:
            weight, bias, _ = layers[-1]
            layers[-1] = (weight, bias, ACTIVATIONS[type(child)])
        else:
            return None
    return layers


class NumpyRollout:
    """Mixin for an ActorCriticPolicy: the rollout forward pass in numpy (module docstring). Falls back to SB3's
    forward in training mode, with gradients on, and for anything but an MLP over flat features with a plain
    diagonal Gaussian."""

    _snapshot: Snapshot | None = None
    _rng: np.random.Generator | None = None

    def set_training_mode(self, mode: bool) -> None:
        super().set_training_mode(mode)  # type: ignore[misc]
        self._snapshot = None if mode else self._take_snapshot()

    def _take_snapshot(self) -> Snapshot | None:
        policy: Any = self
        plain = (isinstance(policy.action_dist, DiagGaussianDistribution) and not policy.squash_output
                 and isinstance(policy.features_extractor, FlattenExtractor) and policy.share_features_extractor)
        if not plain:
            return None
        actor, latent = sequential_layers(policy.mlp_extractor.policy_net), sequential_layers(policy.action_net)
        critic, value = sequential_layers(policy.mlp_extractor.value_net), sequential_layers(policy.value_net)
        if actor is None or latent is None or critic is None or value is None:
            return None
        if self._rng is None:  # seeded from torch's generator: set_random_seed(ppo.seed) fixes both
            self._rng = np.random.default_rng(int(th.randint(0, 2**62, (1,)).item()))
        log_std = policy.log_std.detach().numpy().astype(np.float32).copy()
        return Snapshot(actor + latent, critic + value, log_std, getattr(policy, "actor_dim", None))

    def forward(self, obs: th.Tensor, deterministic: bool = False) -> tuple[th.Tensor, th.Tensor, th.Tensor]:
        snap = self._snapshot
        if snap is None or th.is_grad_enabled():
            return super().forward(obs, deterministic)  # type: ignore[misc]
        x = obs.detach().numpy().reshape(len(obs), -1).astype(np.float32, copy=False)
        mean = mlp(x if snap.actor_dim is None else x[:, : snap.actor_dim], snap.actor)
        values = mlp(x, snap.critic)
        actions, log_prob = gaussian_sample(mean, snap.log_std, self._rng, deterministic)  # type: ignore[arg-type]
        return th.from_numpy(actions), th.from_numpy(values.astype(np.float32)), th.from_numpy(log_prob)


class RolloutPolicy(NumpyRollout, ActorCriticPolicy):
    """SB3's MlpPolicy with the numpy rollout forward."""
