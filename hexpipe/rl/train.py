"""The train-ppo stage: PPO on the CPG-parameter action space with the frozen terrain encoder."""

from __future__ import annotations

import json
import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecEnv, VecEnvWrapper, VecNormalize

from hexpipe.config import Params, params_hash
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.rl.checkpoint import MODEL, NORMALISATION, latest_checkpoint, save_checkpoint, save_policy
from hexpipe.rl.features import TerrainFeatures
from hexpipe.speed import SPEED_JSON, move_speed

POLICY_CONFIG = "policy.json"
PPO_SPEED = ("time",)  # dvclive's time/* metrics: steps per second, measured, not results


def env_factory(params: Params, terrain: str, sensors: tuple[str, ...], randomize: bool) -> Callable[[], HexapodEnv]:
    """A picklable constructor for one environment (SubprocVecEnv builds it in the worker)."""
    task = params.task.model_copy(update={"sensors": sensors})

    def make() -> HexapodEnv:
        return HexapodEnv(
            terrain, sim=params.sim, cpg=params.cpg, sensors=params.sensors, task=task, randomize=randomize
        )

    return make


def make_vec_env(
    params: Params, terrains: tuple[str, ...], n_envs: int, sensors: tuple[str, ...], randomize: bool, seed: int
) -> VecEnv:
    """n_envs raw environments cycling through `terrains`, in worker processes when n_envs > 1."""
    fns = [env_factory(params, terrains[i % len(terrains)], sensors, randomize) for i in range(n_envs)]
    venv = SubprocVecEnv(fns, start_method="fork") if n_envs > 1 else DummyVecEnv(fns)
    venv.seed(seed)
    return venv


def load_terrain_encoder(params: Params):
    """The frozen VAE encoder, or None for a blind policy."""
    if params.ppo.blind:
        return None
    from hexpipe.models.vae import load_encoder

    return load_encoder(params.ppo.encoder_dir)


def wrap_features(venv: VecEnv, encoder, params: Params) -> TerrainFeatures:
    shape = (params.sensors.heightmap_rows, params.sensors.heightmap_cols)
    return TerrainFeatures(venv, encoder, heightmap_shape=shape)


class EnvClock(VecEnvWrapper):
    """Times the raw vectorised env inside training: its own steps/s on the very steps PPO collects.

    Between step_async and step_wait the learner waits on the env workers, so `seconds` is the env's share of the
    run (physics and sensors, no encoder, no learner), measured under the same load as the training around it.
    """

    def __init__(self, venv: VecEnv):
        super().__init__(venv)
        self.steps, self.seconds, self._sent = 0, 0.0, 0.0

    def reset(self):
        return self.venv.reset()

    def step_async(self, actions: np.ndarray) -> None:
        self._sent = time.perf_counter()
        self.venv.step_async(actions)

    def step_wait(self):
        result = self.venv.step_wait()
        self.seconds += time.perf_counter() - self._sent
        self.steps += self.num_envs
        return result

    @property
    def steps_per_s(self) -> float:
        return self.steps / max(self.seconds, 1e-9)


def policy_config(params: Params, encoder, observation_dim: int) -> dict[str, Any]:
    """What evaluate needs to rebuild the policy's input exactly (and to refuse a mismatch)."""
    return {
        "observation_dim": observation_dim,
        "blind": encoder is None,
        "modality": None if encoder is None else encoder.modality,
        "latent_dim": 0 if encoder is None else encoder.latent_dim,
        "encoder_dir": None if encoder is None else str(params.ppo.encoder_dir),
        "sensors": params.sensors.model_dump(mode="json"),
        "sim": params.sim.model_dump(mode="json"),
        "cpg": params.cpg.model_dump(mode="json"),
        "train_terrains": list(params.ppo.train_terrains),
        "randomize": params.ppo.randomize,
    }


def training_signature(params: Params) -> str:
    """Hash of everything a checkpoint depends on except the budget: resuming under other params is refused."""
    return params_hash(params, ppo={"total_timesteps", "checkpoint_every", "report_dir"})


def prepare_checkpoints(checkpoints: Path, signature: str, resume: bool) -> Path | None:
    """The checkpoint to resume from: the newest one if `resume` and it was made under the same params.

    Otherwise the folder is emptied and stamped with this run's signature, so a later --resume can trust it.
    """
    marker = checkpoints / "signature.txt"
    if resume and marker.is_file() and marker.read_text().strip() == signature:
        found = latest_checkpoint(checkpoints)
        if found is not None:
            return found
    shutil.rmtree(checkpoints, ignore_errors=True)
    checkpoints.mkdir(parents=True)
    marker.write_text(signature + "\n")
    return None


def train_ppo(params: Params, resume: bool = False, show_progress: bool = True) -> dict[str, Any]:
    """Train, checkpointing as it goes; returns the final metrics (also written by dvclive)."""
    import torch
    from dvclive import Live

    from hexpipe.rl.callbacks import Checkpoints, EpisodeStats, RichProgress

    cfg = params.ppo
    torch.set_num_threads(1)
    out_dir, report_dir = Path(cfg.out_dir), Path(cfg.report_dir)
    checkpoints = out_dir / "checkpoints"
    encoder = load_terrain_encoder(params)
    sensors = () if encoder is None else (encoder.modality,)
    clock = EnvClock(make_vec_env(params, cfg.train_terrains, cfg.n_envs, sensors, cfg.randomize, cfg.seed))
    venv = wrap_features(clock, encoder, params)

    start_from = prepare_checkpoints(checkpoints, training_signature(params), resume)
    if start_from is not None:
        venv = VecNormalize.load(str(start_from / NORMALISATION), venv)
        model = PPO.load(start_from / MODEL, env=venv, device="cpu")
    else:
        venv = VecNormalize(venv, norm_obs=True, norm_reward=True, clip_obs=10.0, gamma=cfg.gamma)
        model = PPO(
            "MlpPolicy", venv, n_steps=cfg.n_steps, batch_size=cfg.batch_size, n_epochs=cfg.n_epochs,
            learning_rate=cfg.learning_rate, gamma=cfg.gamma, gae_lambda=cfg.gae_lambda, clip_range=cfg.clip_range,
            ent_coef=cfg.ent_coef, policy_kwargs={"net_arch": list(cfg.net_arch)}, seed=cfg.seed, device="cpu",
            verbose=0,
        )

    live = Live(str(report_dir), dvcyaml=False, save_dvc_exp=False, resume=start_from is not None)
    resume_at = model.num_timesteps if start_from is not None else None
    stats = EpisodeStats(live, log_path=report_dir / "episodes.jsonl", resume_at=resume_at)
    callbacks = [stats, Checkpoints(checkpoints, cfg.checkpoint_every)]
    if show_progress:
        callbacks.append(RichProgress(cfg.total_timesteps, stats))
    remaining = cfg.total_timesteps - model.num_timesteps
    started, start_steps = time.perf_counter(), model.num_timesteps
    if remaining > 0:
        model.learn(remaining, callback=callbacks, reset_num_timesteps=start_from is None)
    train_rate = (model.num_timesteps - start_steps) / max(time.perf_counter() - started, 1e-9)
    save_checkpoint(model, checkpoints)
    save_policy(model, out_dir / "policy")
    config = policy_config(params, encoder, int(venv.observation_space.shape[0]))
    tmp = out_dir / (POLICY_CONFIG + ".tmp")
    tmp.write_text(json.dumps(config, indent=2) + "\n")
    tmp.replace(out_dir / POLICY_CONFIG)

    metrics = {
        **stats.recent(),
        "timesteps": model.num_timesteps,
        "time/train_steps_per_s": train_rate,
        "time/bare_env_steps_per_s": clock.steps_per_s,
        # None when resuming a run that had already reached total_timesteps: no step was timed
        "time/train_vs_bare": train_rate / clock.steps_per_s if clock.steps else None,
        "episode/timesteps_to_90pct_success": first_time_success_rate(stats.episodes, threshold=0.9, window=20),
    }
    for name, value in metrics.items():
        if value is not None and name != "timesteps":
            live.log_metric(name, value, plot=False)
    live.make_summary()
    live.end()
    move_speed(report_dir / "metrics.json", report_dir / SPEED_JSON, PPO_SPEED)  # results only in metrics.json
    training_curve(stats.episodes, report_dir / "training_curve.png")
    venv.close()
    return metrics


def training_curve(episodes: list[dict[str, Any]], path: Path, window: int = 20) -> None:
    """The paper's figure 6: episode reward against timesteps, with the rolling success rate beside it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_r, ax_s) = plt.subplots(1, 2, figsize=(10, 3.6))
    if episodes:
        t = np.array([e["timesteps"] for e in episodes])
        reward = np.array([e["reward"] for e in episodes])
        success = np.array([e["success"] for e in episodes], dtype=float)
        k = min(window, len(episodes))
        smooth = np.convolve(reward, np.ones(k) / k, mode="valid")
        rate = np.convolve(success, np.ones(k) / k, mode="valid")
        ax_r.scatter(t, reward, s=4, alpha=0.3, label="episode")
        ax_r.plot(t[k - 1:], smooth, color="C1", label=f"mean of {k}")
        ax_s.plot(t[k - 1:], rate, color="C2")
        ax_r.legend(loc="lower right")
    ax_r.set(xlabel="timesteps", ylabel="episode reward (100 x v_x summed)", title="Episode reward")
    ax_s.set(xlabel="timesteps", ylabel=f"success rate (last {window})", ylim=(-0.02, 1.02), title="Reaches 3 m")
    fig.tight_layout()
    tmp = path.with_name(path.stem + ".tmp.png")
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    tmp.replace(path)


def first_time_success_rate(episodes: list[dict[str, Any]], threshold: float, window: int) -> int | None:
    """Timesteps at which the success rate over the last `window` finished episodes first reached `threshold`."""
    for end in range(window, len(episodes) + 1):
        if np.mean([e["success"] for e in episodes[end - window:end]]) >= threshold:
            return int(episodes[end - 1]["timesteps"])
    return None
