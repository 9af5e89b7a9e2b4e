"""The policy's input: body state + CPG parameters + the frozen VAE embedding of the terrain sensor.

`TerrainFeatures` wraps a VecEnv of raw Dict observations and encodes the sensor once per environment step, batched
across environments, so PPO stores 27 numbers per step and never re-encodes images in its update epochs.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

PROPRIOCEPTIVE_KEYS = ("body", "cpg")


class Encoder(Protocol):
    modality: str
    latent_dim: int

    def encode(self, batch: np.ndarray) -> np.ndarray: ...


class TerrainFeatures(VecEnvWrapper):
    """Dict observations -> one float32 vector [body, cpg, embedding] (no embedding for a blind policy)."""

    def __init__(self, venv: VecEnv, encoder: Encoder | None, frame_shape: tuple[int, ...] | None = None):
        """frame_shape: one sensor reading's shape (`Sensor.frame_shape`), which the encoder takes; the observation
        may hold it flattened (the height map). None: the observation's own shape."""
        self.encoder = encoder
        self.frame_shape = frame_shape
        raw: spaces.Dict = venv.observation_space  # type: ignore[assignment]
        dim = sum(int(np.prod(raw[k].shape)) for k in PROPRIOCEPTIVE_KEYS)
        if encoder is not None:
            if encoder.modality not in raw.spaces:
                raise ValueError(
                    f"encoder modality '{encoder.modality}' is not observed by the env (sensors: {sorted(raw.spaces)})"
                )
            dim += encoder.latent_dim
        super().__init__(venv, observation_space=spaces.Box(-np.inf, np.inf, shape=(dim,), dtype=np.float32))

    def features(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Batched: every value has a leading env axis."""
        parts = [np.asarray(obs[k], dtype=np.float32) for k in PROPRIOCEPTIVE_KEYS]
        if self.encoder is not None:
            sensor = np.asarray(obs[self.encoder.modality])
            if self.frame_shape is not None:
                sensor = sensor.reshape(len(sensor), *self.frame_shape)
            parts.append(self.encoder.encode(sensor).astype(np.float32))
        return np.concatenate(parts, axis=1)

    def reset(self) -> np.ndarray:
        return self.features(self.venv.reset())

    def step_wait(self):
        obs, rewards, dones, infos = self.venv.step_wait()
        terminal = [i for i, info in enumerate(infos) if "terminal_observation" in info]
        if terminal:  # encode all finished episodes' last observations in one batch
            batch = {k: np.stack([infos[i]["terminal_observation"][k] for i in terminal]) for k in obs}
            for i, row in zip(terminal, self.features(batch), strict=True):
                infos[i]["terminal_observation"] = row
        return self.features(obs), rewards, dones, infos
