"""An asymmetric actor-critic for SB3's PPO: the critic reads the whole feature vector, the actor only its first
`actor_dim` numbers (body, CPG, terrain embedding), never the privileged ones that follow (hexpipe/envs/privileged.py).

Only the MLP extractor changes: SB3 builds the policy and value networks from one feature size, so here the policy
network is built for `actor_dim` inputs and fed that slice. Everything else (the Gaussian head, the value head,
the optimiser, PPO's loss) is SB3's own.
"""

from __future__ import annotations

from typing import Any

import torch as th
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.torch_layers import MlpExtractor

from hexpipe.rl.rollout import NumpyRollout


class AsymmetricMlpExtractor(MlpExtractor):
    """SB3's MlpExtractor whose policy network reads features[:, :actor_dim] and value network every feature."""

    def __init__(self, feature_dim: int, actor_dim: int, net_arch: Any, activation_fn: type[th.nn.Module],
                 device: th.device | str = "auto"):
        if not 0 < actor_dim <= feature_dim:
            raise ValueError(f"actor_dim={actor_dim} must be in 1..{feature_dim} (the feature vector's length)")
        super().__init__(feature_dim, net_arch, activation_fn, device)
        self.actor_dim = actor_dim
        self.policy_net = MlpExtractor(actor_dim, net_arch, activation_fn, device).policy_net

    def forward_actor(self, features: th.Tensor) -> th.Tensor:
        return self.policy_net(features[:, : self.actor_dim])


class AsymmetricPolicy(ActorCriticPolicy):
    """ActorCriticPolicy with an `actor_dim` keyword: the actor sees that many leading features, the critic all."""

    def __init__(self, *args: Any, actor_dim: int, **kwargs: Any):
        self.actor_dim = actor_dim  # read by _build_mlp_extractor, which the parent's constructor calls
        super().__init__(*args, **kwargs)

    def _build_mlp_extractor(self) -> None:
        self.mlp_extractor = AsymmetricMlpExtractor(
            self.features_dim, self.actor_dim, net_arch=self.net_arch, activation_fn=self.activation_fn,
            device=self.device,
        )

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return {**super()._get_constructor_parameters(), "actor_dim": self.actor_dim}


class NumpyAsymmetricPolicy(NumpyRollout, AsymmetricPolicy):
    """AsymmetricPolicy with the numpy rollout forward (hexpipe/rl/rollout.py)."""


def actor_only(policy: ActorCriticPolicy) -> ActorCriticPolicy:
    """A plain ActorCriticPolicy over the actor's inputs with the same actor (same action for the same input).

    Its value network is zeroed: the trained critic needs privileged inputs that a running policy never has, so
    the exported file carries no half-usable copy of it.
    """
    if not isinstance(policy, AsymmetricPolicy):
        return policy
    import numpy as np
    from gymnasium import spaces

    space = spaces.Box(-np.inf, np.inf, shape=(policy.actor_dim,), dtype=np.float32)
    plain = ActorCriticPolicy(space, policy.action_space, lr_schedule=lambda _: 0.0, net_arch=policy.net_arch,
                              activation_fn=policy.activation_fn)
    state = plain.state_dict()
    for key, value in policy.state_dict().items():
        state[key] = value if not _is_critic(key) else th.zeros_like(state[key])
    plain.load_state_dict(state)
    plain.set_training_mode(False)
    return plain


def _is_critic(key: str) -> bool:
    return key.startswith(("mlp_extractor.value_net.", "value_net."))
