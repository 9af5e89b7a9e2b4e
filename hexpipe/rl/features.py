"""The policy's input: body state + CPG parameters + the frozen VAE embedding of the terrain sensor.

Two pieces, one per process:

* `TerrainEmbedding` (a gymnasium wrapper, in each env's worker process) replaces the sensor frame with the frozen
  encoder's 8-d posterior mean. Encoding then runs in parallel across the workers, beside their physics, and only
  the embedding crosses the pipe to the learner. Issue 12 moved it here from the learner, where it ran between
  synchronous env steps (about a quarter of train-ppo's time in a profile). Measured by benchmarks/ppo_speedup.py,
  the move gains nothing on 2 cores: 1.00x idle (reports/bench/ppo_speedup_idle.json) and 0.85x with more busy
  processes than cores (reports/bench/ppo_speedup.json), since the 2 workers and the learner leave no core idle.
  It pays where cores are spare (a sweep node).
* `TerrainFeatures` (a VecEnv wrapper, in the learner) lays the Dict out as one float32 vector
  [body, cpg, embedding], so PPO stores 25 numbers per step (27 with task.observe_position) and never re-encodes
  in its update epochs. With ppo.privileged_critic the critic's `privileged` vector follows, last, so the actor
  reads the first `actor_dim` numbers (hexpipe/rl/asymmetric.py).

`feature_vector` is that layout for one raw observation: what a loaded policy computes at run time.
"""

from __future__ import annotations

from typing import Any, Protocol

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

from hexpipe.envs.privileged import PRIVILEGED

PROPRIOCEPTIVE_KEYS = ("body", "cpg")
EMBEDDING = "embedding"  # the observation key TerrainEmbedding adds


class Encoder(Protocol):
    modality: str
    latent_dim: int

    def encode(self, batch: np.ndarray) -> np.ndarray: ...


class TerrainEmbedding(gym.ObservationWrapper):
    """Dict observation with a sensor frame -> the same Dict with `embedding` (latent_dim,) in the frame's place."""

    def __init__(self, env: gym.Env, encoder: Encoder, frame_shape: tuple[int, ...] | None = None):
        """frame_shape: one sensor reading's shape (`Sensor.frame_shape`), which the encoder takes; the observation
        may hold it flattened (the height map). None: the observation's own shape."""
        super().__init__(env)
        raw: spaces.Dict = env.observation_space  # type: ignore[assignment]
        if encoder.modality not in raw.spaces:
            raise ValueError(
                f"encoder modality '{encoder.modality}' is not observed by the env (sensors: {sorted(raw.spaces)})"
            )
        self.encoder = encoder
        self.frame_shape = frame_shape or raw[encoder.modality].shape
        kept = {k: v for k, v in raw.spaces.items() if k != encoder.modality}
        latent = spaces.Box(-np.inf, np.inf, shape=(encoder.latent_dim,), dtype=np.float32)
        self.observation_space = spaces.Dict({**kept, EMBEDDING: latent})

    def observation(self, observation: dict[str, Any]) -> dict[str, Any]:
        out = {k: v for k, v in observation.items() if k != self.encoder.modality}
        out[EMBEDDING] = embed(observation, self.encoder, self.frame_shape)
        return out


def embed(obs: dict[str, Any], encoder: Encoder, frame_shape: tuple[int, ...] | None) -> np.ndarray:
    """The encoder's (latent_dim,) float32 embedding of one observation's sensor frame, reshaped to frame_shape
    (None: as observed)."""
    frame = np.asarray(obs[encoder.modality])
    return encoder.encode(frame.reshape(1, *(frame_shape or frame.shape)))[0].astype(np.float32)


def lay_out(obs: dict[str, Any], keys: tuple[str, ...]) -> np.ndarray:
    """Batched observations (a leading env axis on every value) -> (n, dim) float32, `keys` in order."""
    n = len(obs[keys[0]])
    return np.concatenate([np.asarray(obs[k], dtype=np.float32).reshape(n, -1) for k in keys], axis=1)


def feature_vector(obs: dict[str, Any], encoder: Encoder | None, frame_shape: tuple[int, ...] | None) -> np.ndarray:
    """One raw observation -> (1, dim) float32 [body, cpg, embedding], exactly as training lays it out."""
    if encoder is None:
        return lay_out({k: np.asarray(obs[k])[None] for k in PROPRIOCEPTIVE_KEYS}, PROPRIOCEPTIVE_KEYS)
    keys = (*PROPRIOCEPTIVE_KEYS, EMBEDDING)
    embedded = {**obs, EMBEDDING: embed(obs, encoder, frame_shape)}
    return lay_out({k: np.asarray(embedded[k])[None] for k in keys}, keys)


class TerrainFeatures(VecEnvWrapper):
    """Dict observations (embedded in the envs, or none for a blind policy) -> one float32 vector per env."""

    def __init__(self, venv: VecEnv, expect_embedding: bool | None = None):
        """expect_embedding: True/False refuses envs that do not / do carry an embedding (None: take either)."""
        raw: spaces.Dict = venv.observation_space  # type: ignore[assignment]
        actor_keys = PROPRIOCEPTIVE_KEYS + ((EMBEDDING,) if EMBEDDING in raw.spaces else ())
        self.keys = actor_keys + ((PRIVILEGED,) if PRIVILEGED in raw.spaces else ())
        self.actor_dim = sum(int(np.prod(raw[k].shape)) for k in actor_keys)  # what the policy itself reads
        if expect_embedding is not None and (EMBEDDING in raw.spaces) != expect_embedding:
            raise ValueError(f"the envs {'lack' if expect_embedding else 'carry'} a terrain embedding "
                             f"(observation keys: {sorted(raw.spaces)})")
        dim = sum(int(np.prod(raw[k].shape)) for k in self.keys)
        super().__init__(venv, observation_space=spaces.Box(-np.inf, np.inf, shape=(dim,), dtype=np.float32))

    def features(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Batched: every value has a leading env axis."""
        return lay_out(obs, self.keys)

    def reset(self) -> np.ndarray:
        return self.features(self.venv.reset())

    def step_wait(self):
        obs, rewards, dones, infos = self.venv.step_wait()
        for info in infos:
            if "terminal_observation" in info:
                last = info["terminal_observation"]
                info["terminal_observation"] = self.features({k: np.asarray(last[k])[None] for k in self.keys})[0]
        return self.features(obs), rewards, dones, infos
