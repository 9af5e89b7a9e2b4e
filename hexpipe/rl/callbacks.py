"""Small SB3 callbacks: episode statistics to dvclive, atomic checkpoints, a price ramp and a rich progress bar."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
from stable_baselines3.common.callbacks import BaseCallback

from hexpipe.envs.rewards import ramp
from hexpipe.rl.checkpoint import save_checkpoint


class LiftCostRamp(BaseCallback):
    """Before each rollout, tells every env what share of task.lift_cost to charge (ppo.lift_cost_ramp): 0 until
    `start` timesteps, rising linearly to the whole price at `end`. Read from the model's step count, so a resumed
    run picks the ramp up where its checkpoint left it."""

    def __init__(self, start: int, end: int):
        super().__init__()
        self.start, self.end = start, end
        self.share: float | None = None

    def _on_rollout_start(self) -> None:
        share = ramp(self.model.num_timesteps, self.start, self.end)  # num_timesteps lags until the first step
        if share != self.share:
            self.training_env.env_method("set_lift_cost_share", share)
            self.share = share

    def _on_step(self) -> bool:
        return True


class EpisodeStats(BaseCallback):
    """Collects finished episodes (reward, distance, success, termination) and logs them per rollout.

    Logged against timesteps to dvclive (`episode/*`, `train/*` losses, `time/steps_per_s`): the paper's figure 6
    (episode reward against time) as a DVC plot, plus success rate and distance, and one curve per reward term
    (`episode/reward_<term>`, the env's `info["reward_terms"]` summed over the episode: forward, power, lift,
    failure).
    """

    def __init__(self, live: Any | None = None, window: int = 20, log_path: Path | None = None,
                 resume_at: int | None = None):
        """log_path: episodes.jsonl, appended as episodes end; with resume_at, episodes up to that timestep are
        kept from a previous run (the rest happened after the checkpoint and are replayed)."""
        super().__init__()
        self.live = live
        self.window = window
        self.log_path = log_path
        self.episodes: list[dict[str, Any]] = []
        if log_path is not None:
            if resume_at is not None and log_path.is_file():
                rows = [json.loads(line) for line in log_path.read_text().splitlines() if line.strip()]
                self.episodes = [r for r in rows if r["timesteps"] <= resume_at]
            log_path.parent.mkdir(parents=True, exist_ok=True)
            log_path.write_text("".join(json.dumps(e) + "\n" for e in self.episodes))
        self._returns: np.ndarray | None = None
        self._terms: list[dict[str, float]] = []  # per env: reward terms summed since its episode began
        self._rollout_start = time.perf_counter()
        self._rollout_steps = 0
        self.steps_per_s = 0.0

    def _on_training_start(self) -> None:
        self._returns = np.zeros(self.training_env.num_envs)
        self._terms = [{} for _ in range(self.training_env.num_envs)]

    def _on_rollout_start(self) -> None:
        self._rollout_start = time.perf_counter()
        self._rollout_steps = self.num_timesteps

    def _on_step(self) -> bool:
        rewards = self.locals["rewards"]
        # VecNormalize hands the callback normalised rewards; report the env's own reward
        original = self.model.get_vec_normalize_env()
        if original is not None:
            rewards = original.get_original_reward()
        self._returns += rewards
        for i, done in enumerate(self.locals["dones"]):
            info = self.locals["infos"][i]
            terms = self._terms[i]
            for name, value in info.get("reward_terms", {}).items():
                terms[name] = terms.get(name, 0.0) + float(value)
            if done:
                episode = {
                    "timesteps": self.num_timesteps, "reward": float(self._returns[i]),
                    "distance": float(info.get("distance", 0.0)), "success": bool(info.get("success", False)),
                    "termination": info.get("termination") or "time_limit", "reward_terms": terms,
                }
                self.episodes.append(episode)
                self._returns[i] = 0.0
                self._terms[i] = {}
                if self.log_path is not None:
                    with self.log_path.open("a") as f:
                        f.write(json.dumps(episode) + "\n")
        return True

    def recent(self) -> dict[str, float]:
        last = self.episodes[-self.window:]
        if not last:
            return {}
        names = dict.fromkeys(name for e in last for name in e.get("reward_terms", {}))
        return {
            "episode/reward": float(np.mean([e["reward"] for e in last])),
            **{f"episode/reward_{name}": float(np.mean([e.get("reward_terms", {}).get(name, 0.0) for e in last]))
               for name in names},
            "episode/distance": float(np.mean([e["distance"] for e in last])),
            "episode/success_rate": float(np.mean([e["success"] for e in last])),
            "episode/stuck_rate": float(np.mean([e["termination"] == "stuck" for e in last])),
            "episode/count": float(len(self.episodes)),
        }

    def _on_rollout_end(self) -> None:
        elapsed = time.perf_counter() - self._rollout_start
        self.steps_per_s = (self.num_timesteps - self._rollout_steps) / max(elapsed, 1e-9)
        if self.live is None:
            return
        self.live.step = self.num_timesteps
        for name, value in self.recent().items():
            self.live.log_metric(name, value)
        for name, value in self.model.logger.name_to_value.items():
            if name.startswith("train/"):
                self.live.log_metric(name, float(value))
        self.live.log_metric("time/steps_per_s", self.steps_per_s)
        self.live.make_summary()


class Checkpoints(BaseCallback):
    """Every `every` timesteps, save model + normalisation atomically to `directory` (for `--resume`)."""

    def __init__(self, directory: Path, every: int):
        super().__init__()
        self.directory = Path(directory)
        self.every = every
        self._next = every

    def _on_training_start(self) -> None:
        self._next = (self.num_timesteps // self.every + 1) * self.every

    def _on_step(self) -> bool:
        if self.num_timesteps >= self._next:
            save_checkpoint(self.model, self.directory)
            self._next += self.every
        return True


class RichProgress(BaseCallback):
    """A rich progress bar over timesteps with steps/s and the recent success rate."""

    def __init__(self, total: int, stats: EpisodeStats):
        super().__init__()
        self.total = total
        self.stats = stats
        self.progress = Progress(
            TextColumn("[bold]train-ppo"), BarColumn(), MofNCompleteColumn(),
            TextColumn("{task.fields[rate]:>5.0f} steps/s  success {task.fields[success]:>4.0%}"),
            TimeRemainingColumn(), transient=False,
        )
        self.task = None

    def _on_training_start(self) -> None:
        self.progress.start()
        self.task = self.progress.add_task("ppo", total=self.total, completed=self.num_timesteps, rate=0.0, success=0.0)

    def _on_step(self) -> bool:
        if self.n_calls % 16 == 0:
            recent = self.stats.recent()
            self.progress.update(
                self.task, completed=self.num_timesteps, rate=self.stats.steps_per_s,
                success=recent.get("episode/success_rate", 0.0),
            )
        return True

    def _on_training_end(self) -> None:
        self.progress.update(self.task, completed=self.num_timesteps)
        self.progress.stop()
