"""The train-ppo stage: PPO on the CPG-parameter action space with the frozen terrain encoder."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3 import PPO
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecEnv, VecEnvWrapper, VecNormalize

from hexpipe import sensors as registry
from hexpipe.atomic import atomic_path, write_json, write_text
from hexpipe.config import Params, params_hash
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.rl.asymmetric import AsymmetricPolicy, NumpyAsymmetricPolicy
from hexpipe.rl.checkpoint import (
    MODEL,
    NORMALISATION,
    checkpoint_step,
    complete_checkpoints,
    save_checkpoint,
    save_policy,
)
from hexpipe.rl.curriculum import Curriculum, CurriculumStats
from hexpipe.rl.features import Encoder, TerrainEmbedding, TerrainFeatures
from hexpipe.rl.inference import export_weights
from hexpipe.rl.perturbations import LiftDrops
from hexpipe.rl.rollout import RolloutPolicy
from hexpipe.speed import SPEED_JSON, machine, move_speed
from hexpipe.workers import die_with_parent

POLICY_CONFIG = "policy.json"
PPO_SPEED = ("time",)  # dvclive's time/* metrics: steps per second, measured, not results
# ppo keys that choose among runs but change none of them
SELECTION_ONLY = ("candidates", "validation_episodes", "validation_terrains")


def env_factory(params: Params, terrain: str, encoder: Encoder | None, randomize: bool) -> Callable[[], gym.Env]:
    """A picklable constructor for one environment (SubprocVecEnv builds it in the worker): it observes the
    encoder's sensor and embeds it there (`TerrainEmbedding`); with ppo.curriculum it keeps its own difficulty level
    (hexpipe/rl/curriculum.py); with ppo.lift_drop_rate its lift is knocked to the floor at random moments
    (hexpipe/rl/perturbations.py); with ppo.privileged_critic it adds the critic's privileged vector."""
    parent = os.getpid()
    sensors = () if encoder is None else (encoder.modality,)

    def make() -> gym.Env:
        die_with_parent(parent)  # in a SubprocVecEnv worker: no orphan after a kill -9 of train-ppo
        env: gym.Env = HexapodEnv.from_params(params, terrain, obs_sensors=sensors, randomize=randomize,
                                              privileged=params.ppo.privileged_critic)
        if params.ppo.curriculum:
            env = Curriculum(env, goal=params.task.goal_distance)
        if params.ppo.lift_drop_rate > 0:
            env = LiftDrops(env, params.ppo.lift_drop_rate)
        if encoder is None:
            return env
        import torch

        torch.set_num_threads(1)  # one core per worker: the workers already fill the machine
        return TerrainEmbedding(env, encoder, registry.get(encoder.modality).frame_shape(params.sensors))

    return make


def make_vec_env(
    params: Params, terrains: tuple[str, ...], n_envs: int, encoder: Encoder | None, randomize: bool, seed: int
) -> VecEnv:
    """n_envs environments cycling through `terrains`, in worker processes when n_envs > 1, each embedding its own
    sensor frames with `encoder` (None: blind, no sensor)."""
    fns = [env_factory(params, terrains[i % len(terrains)], encoder, randomize) for i in range(n_envs)]
    venv = SubprocVecEnv(fns, start_method="fork") if n_envs > 1 else DummyVecEnv(fns)
    venv.seed(seed)
    return venv


def policy_class(privileged_critic: bool, numpy_forward: bool) -> type[ActorCriticPolicy]:
    """SB3's MlpPolicy, or the asymmetric one (ppo.privileged_critic), each with SB3's torch rollout forward or the
    numpy one (ppo.rollout_forward)."""
    if privileged_critic:
        return NumpyAsymmetricPolicy if numpy_forward else AsymmetricPolicy
    return RolloutPolicy if numpy_forward else ActorCriticPolicy


def load_terrain_encoder(params: Params):
    """The frozen VAE encoder, or None for a blind policy."""
    if params.ppo.blind:
        return None
    from hexpipe.models.vae import load_encoder

    return load_encoder(params.ppo.encoder_dir, rise_readout=params.ppo.rise_readout)


class EnvClock(VecEnvWrapper):
    """Times the raw vectorised env inside training: its own steps/s on the very steps PPO collects.

    Between step_async and step_wait the learner waits on the env workers, so `seconds` is the env's share of the
    run (physics, sensor and its frozen encoder: the observation the policy consumes; no learner), measured under
    the same load as the training around it.
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
        "observe_position": params.task.observe_position,
        "observe_phase": params.task.observe_phase,
        "privileged_critic": params.ppo.privileged_critic,  # training only: the policy's inputs are the same
        "rise_readout": params.ppo.rise_readout,
    }


def encoder_fingerprint(encoder_dir: str | Path) -> str:
    """Hash of the exported encoder's files (`encoder*` and its rise head in the folder): a retrained VAE is
    another encoder."""
    from hexpipe.models.vae import RISE_HEAD_WEIGHTS

    digest = hashlib.sha256()
    for path in sorted([*Path(encoder_dir).glob("encoder*"), Path(encoder_dir) / RISE_HEAD_WEIGHTS]):
        if path.is_file():
            digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def training_signature(params: Params, encoder_dir: str | Path | None = None) -> str:
    """Hash of everything a checkpoint depends on except the budget (params, code and, unless blind, the encoder's
    files): resuming under anything else is refused. The budget is left out so a longer run extends a shorter one;
    `prepare_checkpoints` makes sure a shorter one never reuses a longer one."""
    base = params_hash(params, ppo={"total_timesteps", "checkpoint_every", "report_dir", *SELECTION_ONLY})
    return base if encoder_dir is None else f"{base}-{encoder_fingerprint(encoder_dir)}"


def signature_encoder(signature: str) -> str:
    """The encoder fingerprint a `training_signature` ends with; '' for a blind policy's (or a missing) one."""
    return signature.partition("-")[2]


def prepare_checkpoints(checkpoints: Path, signature: str, resume: bool, budget: int) -> list[Path]:
    """The checkpoints `--resume` may continue from, newest first: made under the same signature and at or below
    `budget` timesteps (the steps a run of ppo.total_timesteps ends at, a whole number of rollouts).
    When there are none, the folder is emptied and stamped with this run's signature, so a later --resume can trust
    it, and the run starts over."""
    marker = checkpoints / "signature.txt"
    if resume:
        same = marker.is_file() and marker.read_text().strip() == signature
        usable = complete_checkpoints(checkpoints, at_most=budget) if same else []
        if usable:
            return usable
        if not same and complete_checkpoints(checkpoints):
            say(f"train-ppo: the checkpoints in {checkpoints} were made under other params, code or encoder; "
                "starting over")
        elif same and complete_checkpoints(checkpoints):
            say(f"train-ppo: every checkpoint in {checkpoints} is beyond this run's {budget} steps (a shorter budget "
                "never reuses a longer run); starting over")
    shutil.rmtree(checkpoints, ignore_errors=True)
    checkpoints.mkdir(parents=True)
    write_text(marker, signature + "\n")
    return []


def say(message: str) -> None:
    """A one-line note to stderr (beside the progress bar)."""
    from rich.console import Console

    Console(stderr=True).print(message, highlight=False, soft_wrap=True)


def load_checkpoint(candidates: list[Path], venv: VecEnv) -> tuple[PPO, VecNormalize, Path] | None:
    """The newest candidate that loads; a corrupt one (a torn disk, a hand edit) is skipped with a note, so an
    interrupted run falls back to the checkpoint before it. None when none loads."""
    for i, path in enumerate(candidates):
        try:
            normalised = VecNormalize.load(str(path / NORMALISATION), venv)
            model = PPO.load(path / MODEL, env=normalised, device="cpu")
        except Exception as exc:  # any failure to load means: not this one
            later = f"falling back to {candidates[i + 1].name}" if i + 1 < len(candidates) else "starting over"
            say(f"train-ppo: checkpoint {path} is unreadable ({type(exc).__name__}); {later}")
            continue
        return model, normalised, path
    return None


def _finished(out_dir: Path, signature: str, steps: int) -> bool:
    """Whether out_dir's policy is the one this signature's run saved at `steps` (so there is nothing to do)."""
    try:
        config = json.loads((out_dir / POLICY_CONFIG).read_text())
    except (OSError, ValueError):
        return False
    exported = (out_dir / "policy" / MODEL).is_file()
    return exported and config.get("signature") == signature and config.get("timesteps") == steps


def train_ppo(params: Params, resume: bool = False, show_progress: bool = True) -> dict[str, Any]:
    """Train, checkpointing as it goes; returns the final metrics (also written by dvclive).

    With `resume`, continues from the newest loadable checkpoint made under the same signature at or below
    ppo.total_timesteps. A run that already reached the budget is a no-op: `{"finished": True, "timesteps": n}`.
    """
    import torch
    from dvclive import Live

    from hexpipe.rl.callbacks import Checkpoints, EpisodeStats, LiftCostRamp, RichProgress

    cfg = params.ppo
    torch.set_num_threads(1)
    out_dir, report_dir = Path(cfg.out_dir), Path(cfg.report_dir)
    checkpoints = out_dir / "checkpoints"
    encoder = load_terrain_encoder(params)
    signature = training_signature(params, None if encoder is None else cfg.encoder_dir)
    rollout = cfg.n_steps * cfg.n_envs  # PPO stops at the first whole rollout at or past the budget
    reach = -(-cfg.total_timesteps // rollout) * rollout
    candidates = prepare_checkpoints(checkpoints, signature, resume, reach)
    newest = checkpoint_step(candidates[0]) if candidates else 0
    if newest >= cfg.total_timesteps and _finished(out_dir, signature, newest):
        return {"finished": True, "timesteps": newest}
    clock = EnvClock(make_vec_env(params, cfg.train_terrains, cfg.n_envs, encoder, cfg.randomize, cfg.seed))
    features = TerrainFeatures(clock, expect_embedding=encoder is not None)
    venv = features

    loaded = load_checkpoint(candidates, venv) if candidates else None
    if loaded is None and candidates:  # none loads: start over in a clean, re-stamped folder
        prepare_checkpoints(checkpoints, signature, False, reach)
    start_from = None if loaded is None else loaded[2]
    if loaded is not None:
        model, venv = loaded[0], loaded[1]
        say(f"train-ppo: resuming from {start_from} ({model.num_timesteps} of {cfg.total_timesteps} steps)")
    else:
        venv = VecNormalize(venv, norm_obs=True, norm_reward=True, clip_obs=10.0, gamma=cfg.gamma)
        kwargs: dict[str, Any] = {"net_arch": list(cfg.net_arch), "log_std_init": cfg.log_std_init}
        if cfg.privileged_critic:  # the critic reads every feature, the actor the leading actor_dim
            kwargs["actor_dim"] = features.actor_dim
        policy = policy_class(cfg.privileged_critic, cfg.rollout_forward == "numpy")
        model = PPO(
            policy, venv, n_steps=cfg.n_steps, batch_size=cfg.batch_size, n_epochs=cfg.n_epochs,
            learning_rate=cfg.learning_rate, gamma=cfg.gamma, gae_lambda=cfg.gae_lambda, clip_range=cfg.clip_range,
            ent_coef=cfg.ent_coef, use_sde=cfg.use_sde, sde_sample_freq=cfg.sde_sample_freq, policy_kwargs=kwargs,
            seed=cfg.seed, device="cpu", verbose=0,
        )

    live = Live(str(report_dir), dvcyaml=False, save_dvc_exp=False, resume=start_from is not None)
    resume_at = model.num_timesteps if start_from is not None else None
    stats = EpisodeStats(live, log_path=report_dir / "episodes.jsonl", resume_at=resume_at)
    callbacks = [stats, Checkpoints(checkpoints, cfg.checkpoint_every)]
    if cfg.lift_cost_ramp is not None:
        start, end = (round(f * cfg.total_timesteps) for f in cfg.lift_cost_ramp)
        callbacks.insert(0, LiftCostRamp(start, end))  # first: the share is set before the rollout's first step
    if cfg.curriculum:
        callbacks.append(CurriculumStats(live))  # after stats, which sets live.step for this rollout
    if show_progress:
        callbacks.append(RichProgress(cfg.total_timesteps, stats))
    remaining = cfg.total_timesteps - model.num_timesteps
    started, start_steps = time.perf_counter(), model.num_timesteps
    if remaining > 0:
        model.learn(remaining, callback=callbacks, reset_num_timesteps=start_from is None)
    taken = model.num_timesteps - start_steps
    save_checkpoint(model, checkpoints)
    save_policy(model, out_dir / "policy")
    export_weights(model, out_dir / "policy")  # what evaluate and play load: tensors and JSON, no pickle
    config = policy_config(params, encoder, features.actor_dim)
    write_json(out_dir / POLICY_CONFIG, {**config, "signature": signature, "timesteps": int(model.num_timesteps)})

    # rates only when steps were taken now (a resume at the budget just re-exports the policy)
    train_rate = taken / max(time.perf_counter() - started, 1e-9) if taken else None
    bare_rate = clock.steps_per_s if clock.steps else None
    metrics = {
        **stats.recent(),
        "timesteps": model.num_timesteps,
        "time/train_steps_per_s": train_rate,
        "time/bare_env_steps_per_s": bare_rate,
        # None when resuming a run that had already reached total_timesteps: no step was timed
        "time/train_vs_bare": train_rate / bare_rate if train_rate and bare_rate else None,
        "episode/timesteps_to_90pct_success": first_time_success_rate(stats.episodes, threshold=0.9, window=20),
    }
    for name, value in metrics.items():
        if value is not None and name != "timesteps":
            live.log_metric(name, value, plot=False)
    live.make_summary()
    live.end()
    move_speed(report_dir / "metrics.json", report_dir / SPEED_JSON, PPO_SPEED, machine())  # results only in metrics
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
        terms = dict.fromkeys(name for e in episodes for name in e.get("reward_terms", {}))
        for j, name in enumerate(terms):  # each term's share of the sum (forward, minus the power cost)
            term = np.array([e.get("reward_terms", {}).get(name, 0.0) for e in episodes])
            if np.any(term):
                ax_r.plot(t[k - 1:], np.convolve(term, np.ones(k) / k, mode="valid"), color=f"C{3 + j}",
                          linestyle="--", label=f"{name} term, mean of {k}")
        ax_s.plot(t[k - 1:], rate, color="C2")
        ax_r.legend(loc="lower right")
    ax_r.set(xlabel="timesteps", ylabel="episode reward (sum of the terms)", title="Episode reward")
    ax_s.set(xlabel="timesteps", ylabel=f"success rate (last {window})", ylim=(-0.02, 1.02), title="Reaches 3 m")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)


def first_time_success_rate(episodes: list[dict[str, Any]], threshold: float, window: int) -> int | None:
    """Timesteps at which the success rate over the last `window` finished episodes first reached `threshold`."""
    for end in range(window, len(episodes) + 1):
        if np.mean([e["success"] for e in episodes[end - window:end]]) >= threshold:
            return int(episodes[end - 1]["timesteps"])
    return None
