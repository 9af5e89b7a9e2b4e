"""The weights-only form of a trained policy: written by train-ppo, read by evaluate, play and `load_policy`.

SB3 saves a model as a zip whose `data` entry holds cloudpickled objects, and VecNormalize as a pickle; loading
either runs whatever code the file names. They stay for `train-ppo --resume` (your own checkpoints only). For
running a policy, train-ppo also writes, into the same folder:

- `weights.pt`: the state dict of SB3's ActorCriticPolicy (tensors only; read with `torch.load(weights_only=True)`);
- `weights.json`: what rebuilds that network (observation and action sizes, net_arch, activation) and the frozen
  observation normalisation (VecNormalize's running mean and variance, epsilon and clip), as plain numbers.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from hexpipe.atomic import write_text
from hexpipe.models.weights import WeightsError, load_state_dict, save_state_dict

WEIGHTS = "weights.pt"
WEIGHTS_CONFIG = "weights.json"
FORMAT_VERSION = 1
# Activations a policy may name (SB3's MlpPolicy default is Tanh); looked up in torch.nn, never imported by name.
ACTIVATIONS = ("Tanh", "ReLU", "ELU", "LeakyReLU", "SiLU", "GELU")


@dataclass(frozen=True)
class ObservationNormaliser:
    """VecNormalize's observation transform with frozen statistics: clip((x - mean) / sqrt(var + eps), +-clip)."""

    mean: np.ndarray  # (observation_dim,) float64
    var: np.ndarray
    epsilon: float
    clip: float

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return np.clip((x - self.mean) / np.sqrt(self.var + self.epsilon), -self.clip, self.clip).astype(np.float32)


def without_sde_noise(policy: Any) -> Any:
    """A gSDE policy (ppo.use_sde) as a plain ActorCriticPolicy with the same networks: its noise scales (one per
    hidden feature and action) drive exploration in training only, and the deterministic action never reads them.
    The copy's log_std is SB3's default (zeros); a policy without gSDE is returned as it is."""
    if not getattr(policy, "use_sde", False):
        return policy
    from stable_baselines3.common.policies import ActorCriticPolicy

    plain = ActorCriticPolicy(policy.observation_space, policy.action_space, lr_schedule=lambda _: 0.0,
                              net_arch=policy.net_arch, activation_fn=policy.activation_fn)
    state = plain.state_dict()
    state.update({k: v for k, v in policy.state_dict().items() if k != "log_std"})
    plain.load_state_dict(state)
    plain.set_training_mode(False)
    return plain


def export_weights(model: Any, directory: Path) -> None:
    """Write weights.pt and weights.json for `model` (SB3 PPO, MlpPolicy) and its VecNormalize into `directory`.

    An asymmetric policy (ppo.privileged_critic) is written as its actor alone, over the actor's inputs: the
    privileged features and their normalisation are left out (`asymmetric.actor_only`); a gSDE policy is written
    without its noise scales (`without_sde_noise`)."""
    from hexpipe.rl.asymmetric import actor_only

    policy = without_sde_noise(actor_only(model.policy))
    dim = int(np.prod(policy.observation_space.shape))
    normaliser = model.get_vec_normalize_env()
    norm = None
    if normaliser is not None and normaliser.norm_obs:  # the leading `dim` features are the actor's
        norm = {"mean": normaliser.obs_rms.mean[:dim].tolist(), "var": normaliser.obs_rms.var[:dim].tolist(),
                "epsilon": float(normaliser.epsilon), "clip": float(normaliser.clip_obs)}
    space = policy.action_space
    config = {
        "format_version": FORMAT_VERSION,
        "observation_dim": dim,
        "action_low": space.low.tolist(),
        "action_high": space.high.tolist(),
        "net_arch": policy.net_arch,
        "activation": policy.activation_fn.__name__,
        "observation_normalisation": norm,
    }
    save_state_dict(policy.state_dict(), Path(directory) / WEIGHTS)
    write_text(Path(directory) / WEIGHTS_CONFIG, json.dumps(config, indent=2) + "\n")


def load_weights(directory: Path) -> tuple[Any, ObservationNormaliser | None, dict[str, Any]]:
    """(SB3 ActorCriticPolicy in eval mode, observation normaliser or None, weights.json) from `directory`.

    WeightsError (one line naming the file) for anything missing, corrupt or inconsistent.
    """
    import torch
    from gymnasium import spaces
    from stable_baselines3.common.policies import ActorCriticPolicy

    config_path = Path(directory) / WEIGHTS_CONFIG
    config = _read_config(config_path)
    dim = config["observation_dim"]
    observation_space = spaces.Box(-np.inf, np.inf, shape=(dim,), dtype=np.float32)
    low, high = (np.asarray(config[k], dtype=np.float32) for k in ("action_low", "action_high"))
    action_space = spaces.Box(low, high)
    state = load_state_dict(Path(directory) / WEIGHTS)
    try:
        policy = ActorCriticPolicy(observation_space, action_space, lr_schedule=lambda _: 0.0,
                                   net_arch=config["net_arch"], activation_fn=getattr(torch.nn, config["activation"]))
        policy.load_state_dict(state)
    except (RuntimeError, TypeError, ValueError, KeyError) as exc:
        text = " ".join(str(exc).split())[:300]
        raise WeightsError(f"{Path(directory) / WEIGHTS}: does not match {config_path} ({text})") from None
    policy.set_training_mode(False)
    norm = config["observation_normalisation"]
    normaliser = None if norm is None else ObservationNormaliser(
        np.asarray(norm["mean"], dtype=np.float64), np.asarray(norm["var"], dtype=np.float64),
        float(norm["epsilon"]), float(norm["clip"]),
    )
    return policy, normaliser, config


def _read_config(path: Path) -> dict[str, Any]:
    """weights.json, every field checked: a bad file is one line, never a traceback later."""
    if not path.is_file():
        raise WeightsError(f"{path}: not found")
    try:
        config = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise WeightsError(f"{path}: unreadable ({type(exc).__name__}: {exc})") from None
    if not isinstance(config, dict):
        raise WeightsError(f"{path}: expected a JSON object, found {type(config).__name__}")
    if config.get("format_version") != FORMAT_VERSION:
        raise WeightsError(f"{path}: format_version {config.get('format_version')!r}, expected {FORMAT_VERSION}")
    dim = config.get("observation_dim")
    if not (isinstance(dim, int) and 0 < dim <= 100_000):
        raise WeightsError(f"{path}: observation_dim must be a positive integer, found {dim!r}")
    low, high = config.get("action_low"), config.get("action_high")
    if not (_numbers(low) and _numbers(high) and len(low) == len(high) > 0
            and all(a <= b for a, b in zip(low, high, strict=True))):
        raise WeightsError(f"{path}: action_low/action_high must be equal-length lists of finite bounds, low <= high")
    if not _valid_arch(config.get("net_arch")):
        raise WeightsError(f"{path}: net_arch must be a list of layer widths or {{pi: [...], vf: [...]}}")
    if config.get("activation") not in ACTIVATIONS:
        raise WeightsError(f"{path}: activation {config.get('activation')!r} is not one of {', '.join(ACTIVATIONS)}")
    norm = config.get("observation_normalisation")
    if norm is not None:
        ok = (isinstance(norm, dict) and _numbers(norm.get("mean")) and _numbers(norm.get("var"))
              and len(norm["mean"]) == len(norm["var"]) == dim and min(norm["var"], default=0) >= 0
              and _numbers([norm.get("epsilon"), norm.get("clip")]) and norm["epsilon"] > 0 and norm["clip"] > 0)
        if not ok:
            raise WeightsError(f"{path}: observation_normalisation needs mean and var of length {dim} (var >= 0), "
                               "epsilon > 0 and clip > 0")
    return config


def _numbers(values: Any) -> bool:
    return isinstance(values, list) and all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in values
    )


def _valid_arch(arch: Any) -> bool:
    def widths(v: Any) -> bool:
        return isinstance(v, list) and len(v) <= 16 and all(
            isinstance(w, int) and not isinstance(w, bool) and 0 < w <= 4096 for w in v
        )

    if isinstance(arch, dict):
        return set(arch) <= {"pi", "vf"} and all(widths(v) for v in arch.values())
    return widths(arch)
