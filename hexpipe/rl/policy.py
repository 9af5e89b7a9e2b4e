"""Loading a trained PPO policy to run it, with its inputs rebuilt exactly as in training; no pickle is read.

train-ppo writes `<dir>/policy.json` and, in `<dir>/policy/`, the weights-only files `weights.pt` and
`weights.json` (see `hexpipe.rl.inference`) beside SB3's `model.zip` and `vecnormalize.pkl` (kept only for
`--resume`). At run time the policy must see the same vector it was trained on: [body, cpg, embedding] (the
`TerrainFeatures` layout), normalised with the frozen training statistics. Everything that would silently change
that vector (another height map size or extent, a retrained VAE of another latent size, a blind policy where a
seeing one is expected) is refused up front with a one-line `PolicyError` saying what was expected and found.

`hexpipe.load_policy(dir)` is this module's `load_policy` without params: the env settings then come from
policy.json (those the policy was trained with).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from hexpipe import sensors as registry
from hexpipe.config import CpgConfig, Params, SensorConfig, SimConfig
from hexpipe.rl.features import PROPRIOCEPTIVE_KEYS, Encoder, feature_vector
from hexpipe.rl.inference import WEIGHTS, WEIGHTS_CONFIG, ObservationNormaliser, load_weights
from hexpipe.rl.train import POLICY_CONFIG, encoder_fingerprint, signature_encoder
from hexpipe.validation import one_line

POLICY_SUBDIR = "policy"  # train.py saves the policy files here
_RETRAIN = "run `hexpipe train-ppo`"
# the task's observation settings a policy.json records (they shape the policy's input), each with what a policy.json
# from before the setting existed means: those policies saw x, y and no phase
_OBSERVATION_SETTINGS = (("observe_position", True), ("observe_phase", False))
_ACTION_MEANING = {1: "the rates of a, b, omega", 2: "the second derivatives of a, b, omega"}


class PolicyError(ValueError):
    """A missing, incomplete or incompatible trained policy; one line naming the path and what is wrong."""


@dataclass
class LoadedPolicy:
    """A frozen PPO policy: one raw env observation (the Dict from reset/step) in, deterministic action (3,) out.

    `env_kwargs` are the HexapodEnv settings it expects (sim, cpg, sensors, and task with the policy's sensors):
    `gymnasium.make("hexpipe/Hexapod-v0", terrain=..., **policy.env_kwargs)`.
    """

    name: str  # e.g. "ppo+heightmap-vae8" or "ppo-blind"
    directory: Path
    config: dict[str, Any]  # policy.json
    actor: Any  # stable_baselines3 ActorCriticPolicy, eval mode, rebuilt from weights.pt
    normaliser: ObservationNormaliser | None  # the frozen VecNormalize statistics; None if trained without
    encoder: Encoder | None
    params: Params  # the settings the env must be built with
    drift: list[str] = field(default_factory=list)  # sim/cpg settings that differ from training (warnings)

    @property
    def blind(self) -> bool:
        return self.encoder is None

    @property
    def sensors(self) -> tuple[str, ...]:
        """The observation sensors the env must provide (none for a blind policy)."""
        return () if self.encoder is None else (self.encoder.modality,)

    @property
    def env_kwargs(self) -> dict[str, Any]:
        p = self.params
        return {"sim": p.sim, "cpg": p.cpg, "sensors": p.sensors,
                "task": p.task.model_copy(update={"sensors": self.sensors})}

    def features(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """One observation -> (1, observation_dim) float32, laid out as `TerrainFeatures.features`."""
        shape = None if self.encoder is None else registry.get(self.encoder.modality).frame_shape(self.params.sensors)
        return feature_vector(obs, self.encoder, shape)

    def predict(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Deterministic action in [-1, 1]^3 (d²/dt² of a, b, omega, scaled) for one raw observation."""
        x = self.features(obs)
        if self.normaliser is not None:
            x = self.normaliser(x)
        action, _ = self.actor.predict(x, deterministic=True)
        return np.asarray(action, dtype=np.float32).reshape(-1)


def load_policy(
    policy_dir: str | Path, params: Params | None = None, expect_blind: bool | None = None
) -> LoadedPolicy:
    """Load and check the policy trained into `policy_dir` (train-ppo's ppo.out_dir).

    params: the settings to run it under (checked against training); None: those it was trained with
    (policy.json). expect_blind: True/False refuses a policy that is not / is blind (None accepts either).
    """
    directory = Path(policy_dir)
    if not directory.is_dir():
        raise PolicyError(f"no trained policy at {directory}: folder not found ({_RETRAIN} first)")
    config_path = directory / POLICY_CONFIG
    weights_dir = directory / POLICY_SUBDIR
    for path in (config_path, weights_dir / WEIGHTS, weights_dir / WEIGHTS_CONFIG):
        if not path.is_file():
            raise PolicyError(f"incomplete policy in {directory}: {path} not found ({_RETRAIN})")
    config = _read_config(config_path)
    given = params is not None
    if params is None:
        params = _training_params(config, config_path)
    blind = bool(config["blind"])
    if expect_blind is not None and blind != expect_blind:
        want, got = ("blind", "one that sees the terrain") if expect_blind else ("seeing", "a blind one")
        raise PolicyError(f"{directory}: expected a {want} policy, found {got} (policy.json blind={blind})")

    for key, before in _OBSERVATION_SETTINGS:
        trained = config.get(key, before)
        if trained != getattr(params.task, key):
            raise PolicyError(
                f"{directory}: policy was trained with task.{key}={str(trained).lower()}, params now have "
                f"{str(getattr(params.task, key)).lower()}; evaluate with the training setting or {_RETRAIN}"
            )
    trained_order = (_recorded(config, "cpg") or {}).get("action_order", 2)  # 2 before the setting existed
    if trained_order != params.cpg.action_order:
        meaning = _ACTION_MEANING.get(trained_order, "unknown")
        raise PolicyError(
            f"{directory}: policy was trained with cpg.action_order={trained_order} (its actions are {meaning}), "
            f"params now have {params.cpg.action_order}; evaluate with the training setting or {_RETRAIN}"
        )
    encoder = None if blind else _load_matching_encoder(directory, config, params)
    dim = int(config["observation_dim"])
    produced = feature_dim(params, 0 if encoder is None else encoder.latent_dim)
    if produced != dim:
        raise PolicyError(
            f"{directory}: policy expects {dim} input features (policy.json observation_dim), but the env and "
            f"encoder now produce {produced}; evaluate with the training settings or {_RETRAIN}"
        )

    from hexpipe.models.weights import WeightsError

    try:
        actor, normaliser, weights = load_weights(weights_dir)
    except WeightsError as exc:
        raise PolicyError(f"{directory}: cannot load the policy weights: {exc} ({_RETRAIN})") from None
    if weights["observation_dim"] != dim:
        raise PolicyError(
            f"{directory}: expected observation_dim={dim} (policy.json), found {weights['observation_dim']} in "
            f"{WEIGHTS_CONFIG}; the files come from different runs ({_RETRAIN})"
        )

    latent = "" if encoder is None else f"+{encoder.modality}-vae{encoder.latent_dim}"
    return LoadedPolicy(
        name="ppo-blind" if encoder is None else f"ppo{latent}",
        directory=directory, config=config, actor=actor, normaliser=normaliser, encoder=encoder, params=params,
        drift=_drift(config, params) if given else [],
    )


def _training_params(config: dict[str, Any], path: Path) -> Params:
    """Params with the sim, cpg and sensor settings and the task's observation settings recorded in policy.json
    (everything else: defaults)."""
    from pydantic import ValidationError

    sections: dict[str, Any] = {"task": {key: config.get(key, before) for key, before in _OBSERVATION_SETTINGS}}
    for name, model in (("sim", SimConfig), ("cpg", CpgConfig), ("sensors", SensorConfig)):
        recorded = _recorded(config, name)
        if not isinstance(recorded, dict):
            raise PolicyError(f"{path}: policy config lacks the {name} settings; pass params or {_RETRAIN}")
        sections[name] = {k: v for k, v in recorded.items() if k in model.model_fields}
    try:
        return Params.model_validate(sections)
    except ValidationError as exc:
        raise PolicyError(f"{path}: recorded settings are invalid ({exc.errors()[0]['msg']})") from None


def _recorded(config: dict[str, Any], section: str) -> Any:
    """policy.json's settings of one section. A policy recorded before `cpg.lift_follows` existed was trained
    without it: its default has been true since."""
    recorded = config.get(section)
    if section == "cpg" and isinstance(recorded, dict):
        recorded = {"lift_follows": False, **recorded}
    return recorded


def _read_config(path: Path) -> dict[str, Any]:
    try:
        config = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise PolicyError(f"{path}: unreadable policy config ({one_line(exc)}); {_RETRAIN}") from None
    required = ("observation_dim", "blind", "modality", "latent_dim", "encoder_dir", "sensors")
    missing = [k for k in required if k not in config] if isinstance(config, dict) else list(required)
    if missing:
        raise PolicyError(f"{path}: policy config lacks {', '.join(missing)}; {_RETRAIN}")
    return config


def _load_matching_encoder(directory: Path, config: dict[str, Any], params: Params) -> Encoder:
    """The policy's frozen encoder, checked against policy.json and the sensor settings now."""
    from hexpipe.models.vae import EncoderError, load_encoder

    modality, encoder_dir = config["modality"], config["encoder_dir"]
    before = SensorConfig().model_dump(mode="json")  # a key policy.json lacks predates it: trained at its default
    for key in registry.get(modality).config_keys:  # settings that change what its frames mean
        trained, now = config["sensors"].get(key, before[key]), params.sensors.model_dump(mode="json")[key]
        if trained != now:
            raise PolicyError(
                f"{directory}: policy was trained with sensors.{key}={trained}, params now have {now} "
                f"(expected {trained}, found {now}); evaluate with the training sensor settings or {_RETRAIN}"
            )
    try:
        encoder = load_encoder(encoder_dir, rise_readout=bool(config.get("rise_readout", False)))
    except EncoderError as exc:
        raise PolicyError(f"{directory}: the policy's terrain encoder at {encoder_dir} is unusable: {exc}") from None
    trained_with = signature_encoder(str(config.get("signature", "")))  # the encoder's fingerprint at training time
    if trained_with and (found := encoder_fingerprint(encoder_dir)) != trained_with:
        raise PolicyError(
            f"{directory}: the terrain encoder at {encoder_dir} is not the one the policy was trained with "
            f"(expected fingerprint {trained_with}, found {found}); the VAE was retrained after the policy "
            f"({_RETRAIN}, or point policy.json's encoder_dir at the encoder it was trained with)"
        )
    if encoder.modality != modality or encoder.latent_dim != int(config["latent_dim"]):
        raise PolicyError(
            f"{directory}: expected a {modality} encoder with latent_dim={config['latent_dim']} (policy.json), "
            f"found {encoder.modality} with latent_dim={encoder.latent_dim} at {encoder_dir}; the VAE was "
            f"retrained after the policy ({_RETRAIN})"
        )
    shape = registry.get(modality).frame_shape(params.sensors)
    if tuple(encoder.input_shape) != shape:
        raise PolicyError(
            f"{directory}: encoder at {encoder_dir} expects {modality} frames of shape {tuple(encoder.input_shape)},"
            f" params.sensors now give {shape}"
        )
    return encoder


def feature_dim(params: Params, latent_dim: int) -> int:
    """Length of the policy's input: the env's proprioceptive keys (its observation space now) and the terrain
    encoder's latent_dim (0 for a blind policy)."""
    from hexpipe.envs.hexapod import HexapodEnv

    spaces = HexapodEnv.observation_spec(params, obs_sensors=()).spaces
    dim = sum(int(np.prod(spaces[k].shape)) for k in PROPRIOCEPTIVE_KEYS)
    return dim + latent_dim


def _drift(config: dict[str, Any], params: Params) -> list[str]:
    """`key: trained -> now` for sim/cpg settings and training terrains changed since training (allowed: they do
    not change the input layout, but worth reporting)."""
    out = []
    for section in ("sim", "cpg"):
        now = getattr(params, section).model_dump(mode="json")
        for key, trained in (_recorded(config, section) or {}).items():
            if key in now and now[key] != trained:
                out.append(f"{section}.{key}: {trained} -> {now[key]}")
    trained_on = config.get("train_terrains")
    if trained_on is not None and trained_on != list(params.ppo.train_terrains):
        out.append(f"ppo.train_terrains: {trained_on} -> {list(params.ppo.train_terrains)}")
    return out

