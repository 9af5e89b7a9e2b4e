"""Speed benchmarks: env steps per second (default config, the pre-issue-12 physics, physics only, + height map,
+ camera, per terrain) and PPO training steps per second against the bare env rate.

Configurations are interleaved window by window (A B C A B C ...) so that machine noise hits all of them alike,
and medians are reported. Sensor costs are also timed directly (one sensor read per control step), which is the
sharper number: an env step is mostly physics, and its noise is larger than a height map read.
"""

from __future__ import annotations

import os
import statistics
import time
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from hexpipe import sensors as registry
from hexpipe.config import Params, SimConfig
from hexpipe.envs.hexapod import HexapodEnv

SENSOR_SETS = {"physics": (), "heightmap": ("heightmap",), "camera": ("rgb",)}
# The physics before issue 12: 240 Hz, PyBullet's default solver (50 iterations), the same servo bandwidth
BASELINE_SIM = {"physics_hz": 240, "solver_iterations": 50, "position_gain": 0.3}


def baseline_sim(sim: SimConfig) -> SimConfig:
    """`sim` with the pre-issue-12 physics rate, solver and position gain (everything else kept)."""
    return sim.model_copy(update=BASELINE_SIM)


@contextmanager
def _one_core() -> Iterator[None]:
    """Run on one core (the env is single-threaded; this keeps its timing apart from the scheduler), then restore."""
    if not hasattr(os, "sched_setaffinity"):
        yield
        return
    cores = os.sched_getaffinity(0)
    os.sched_setaffinity(0, {min(cores)})
    try:
        yield
    finally:
        os.sched_setaffinity(0, cores)


def _window(env: HexapodEnv, steps: int) -> float:
    """Median-friendly: seconds per env step over `steps` steps (resetting on episode end)."""
    start = time.perf_counter()
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(np.zeros(3))
        if terminated or truncated:
            env.reset()
    return (time.perf_counter() - start) / steps


def bench_env(params: Params, terrains: tuple[str, ...], windows: int = 7, steps: int = 60) -> dict:
    """Env step rate (steps/s, one core) for each terrain and sensor set, plus direct sensor read costs.

    `default` is the env as configured (its own sensors); `baseline` the same env with the pre-issue-12 physics
    (`BASELINE_SIM`), so `speedup_vs_baseline` is what the physics settings buy, measured in the same windows.
    """
    with _one_core():
        return _bench_env(params, terrains, windows, steps)


def _bench_env(params: Params, terrains: tuple[str, ...], windows: int, steps: int) -> dict:
    results: dict = {"windows": windows, "steps_per_window": steps, "control_hz": params.sim.control_hz,
                     "sim": params.sim.model_dump(mode="json"), "baseline_sim": BASELINE_SIM}
    for terrain in terrains:
        sims = dict.fromkeys(SENSOR_SETS, params.sim) | {"default": params.sim, "baseline": baseline_sim(params.sim)}
        sensor_sets = SENSOR_SETS | {"default": params.task.sensors, "baseline": params.task.sensors}
        envs = {
            name: HexapodEnv.from_params(params.model_copy(update={"sim": sims[name]}), terrain, obs_sensors=sensors)
            for name, sensors in sensor_sets.items()
        }
        for env in envs.values():
            env.reset(seed=0)
            _window(env, 5)  # warm-up
        times: dict[str, list[float]] = {name: [] for name in envs}
        for _ in range(windows):
            for name, env in envs.items():
                times[name].append(_window(env, steps))
        row = {name: {"ms_per_step": 1e3 * statistics.median(t), "steps_per_s": 1 / statistics.median(t)}
               for name, t in times.items()}
        physics = statistics.median(times["physics"])
        row["speedup_vs_baseline"] = statistics.median(times["baseline"]) / statistics.median(times["default"])
        for name in ("heightmap", "camera"):
            row[name]["overhead_vs_physics"] = statistics.median(times[name]) / physics - 1

        row["heightmap_read_ms"], row["camera_read_ms"] = _sensor_read_ms(envs)
        row["heightmap_read_vs_physics_step"] = row["heightmap_read_ms"] / row["physics"]["ms_per_step"]
        results[terrain] = row
        for env in envs.values():
            env.close()
    return results


def _sensor_read_ms(envs: dict[str, HexapodEnv]) -> tuple[float, float]:
    """Median cost (ms) of one height-map read and one camera frame at the robot's current pose."""
    hm_env, cam_env = envs["heightmap"], envs["camera"]
    hm_view, cam_view = hm_env.view(), cam_env.view()
    hm_read, cam_read = hm_env.reader("heightmap"), cam_env.reader("rgb")
    heightmap = _median_call(lambda: hm_read(hm_view))
    camera = _median_call(lambda: cam_read(cam_view), repeats=50)
    return 1e3 * heightmap, 1e3 * camera


def _median_call(fn, repeats: int = 300) -> float:
    fn()
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)


FORWARDS = ("numpy", "torch")  # the rollout forward pass (ppo.rollout_forward): hexpipe/rl/rollout.py's, SB3's own


def bench_training(params: Params, steps: int = 3072, terrain: str | None = None, rounds: int = 2) -> dict:
    """PPO training steps/s with `ppo.n_envs` worker envs against the bare vectorised env rate in the same run,
    with the numpy rollout forward and with SB3's torch one, alternated for `rounds` rounds (medians); the top-level
    figures are those of the configured one (ppo.rollout_forward).

    The policy sees what `train-ppo` gives it (an encoder of the configured VAE shape, untrained: its weights do
    not change its cost), embedded in the env workers as in training. `bare_env_steps_per_s` is timed inside each
    run (rl.train.EnvClock: physics, sensor and encoder, the observation the policy consumes), so both numbers share
    the machine's load. Budget: `steps` timesteps per run, a few PPO rollouts and updates.
    """
    runs: dict[str, list[dict]] = {name: [] for name in FORWARDS}
    for _ in range(rounds):
        for name in FORWARDS:
            runs[name].append(_training_run(params, steps, terrain, numpy_forward=name == "numpy"))
    out: dict = {}
    for name, results in runs.items():
        out[name] = {key: statistics.median(r[key] for r in results)
                     for key in ("train_steps_per_s", "bare_env_steps_per_s", "train_vs_bare", "seconds")}
    first = runs["numpy"][0]
    return {"n_envs": first["n_envs"], "timesteps": first["timesteps"], "terrains": first["terrains"],
            "encoder": first["encoder"], "rounds": rounds, "rollout_forward": params.ppo.rollout_forward,
            **out[params.ppo.rollout_forward], "forwards": out,
            "numpy_vs_torch_forward": out["numpy"]["train_steps_per_s"] / out["torch"]["train_steps_per_s"],
            "forward_us": forward_cost(params)}


def forward_cost(params: Params, calls: int = 2000) -> dict[str, float]:
    """Median microseconds of one rollout forward pass (a batch of ppo.n_envs observations of the policy's size,
    no gradient), SB3's torch forward against the numpy one, on the same network."""
    import torch
    from gymnasium import spaces
    from stable_baselines3.common.policies import ActorCriticPolicy

    from hexpipe.rl.policy import feature_dim
    from hexpipe.rl.rollout import RolloutPolicy

    torch.set_num_threads(1)
    dim = feature_dim(params, 0 if params.ppo.blind else params.vae.latent_dim)
    space = spaces.Box(-np.inf, np.inf, shape=(dim,), dtype=np.float32)
    policy = RolloutPolicy(space, spaces.Box(-1, 1, (3,)), lr_schedule=lambda _: 0.0,
                           net_arch=list(params.ppo.net_arch))
    obs = torch.as_tensor(np.random.default_rng(0).normal(size=(params.ppo.n_envs, dim)).astype(np.float32))
    forwards = {"numpy": policy.forward, "torch": lambda x: ActorCriticPolicy.forward(policy, x)}
    policy.set_training_mode(False)
    out = {}
    with torch.no_grad():
        for name, forward in forwards.items():
            out[name] = 1e6 * _median_call(lambda f=forward: f(obs), repeats=calls)
    return out


def _training_run(params: Params, steps: int, terrain: str | None, numpy_forward: bool) -> dict:
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from hexpipe.models.vae import ConvVAE, FrozenEncoder, channels_for, encoder_config
    from hexpipe.rl.features import TerrainFeatures
    from hexpipe.rl.rollout import RolloutPolicy
    from hexpipe.rl.train import EnvClock, make_vec_env

    cfg, vae = params.ppo, params.vae
    torch.set_num_threads(1)
    encoder = None
    if not cfg.blind:
        shape = registry.get(vae.modality).frame_shape(params.sensors)
        model = ConvVAE(channels_for(vae.modality), vae.image_size, vae.latent_dim)
        encoder = FrozenEncoder(model.encoder, encoder_config(model, vae.modality, shape))
    terrains = (terrain,) if terrain else cfg.train_terrains
    clock = EnvClock(make_vec_env(params, terrains, cfg.n_envs, encoder, cfg.randomize, cfg.seed))
    venv = VecNormalize(TerrainFeatures(clock), norm_obs=True, norm_reward=True, gamma=cfg.gamma)
    agent = PPO(
        RolloutPolicy if numpy_forward else "MlpPolicy", venv, n_steps=cfg.n_steps, batch_size=cfg.batch_size,
        n_epochs=cfg.n_epochs, learning_rate=cfg.learning_rate, gamma=cfg.gamma, gae_lambda=cfg.gae_lambda,
        clip_range=cfg.clip_range, policy_kwargs={"net_arch": list(cfg.net_arch)}, seed=cfg.seed, device="cpu",
        verbose=0,
    )
    start = time.perf_counter()
    agent.learn(steps)
    seconds = time.perf_counter() - start
    venv.close()
    train = agent.num_timesteps / seconds
    return {"n_envs": cfg.n_envs, "timesteps": agent.num_timesteps, "seconds": seconds, "terrains": list(terrains),
            "encoder": encoder is not None, "train_steps_per_s": train,
            "bare_env_steps_per_s": clock.steps_per_s, "train_vs_bare": train / clock.steps_per_s}
