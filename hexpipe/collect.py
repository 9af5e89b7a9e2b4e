"""The collect stage: random-policy rollouts over a terrain mix, logged to MCAP, with a manifest and a report.

As in the paper, the robot walks "with a random policy": every control step draws a random second derivative of
(a, b, omega) within +-`action_scale`. Episodes are planned up front from (collect.seed, episode index), so the
dataset is reproducible and a rerun after an interruption only runs the episodes whose files are missing. Each
file appears under its final name only when complete (see `EpisodeWriter`), and the manifest is rewritten
atomically after every finished episode: it never lists a file that cannot be read.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np

from hexpipe.config import Params, params_hash
from hexpipe.envs.hexapod import HexapodEnv

MANIFEST = "manifest.json"
TIMINGS = ("seconds", "env_seconds")  # wall-clock figures: reported, never in the (reproducible) manifest


@dataclass(frozen=True)
class EpisodePlan:
    index: int
    terrain: str
    seed: int

    @property
    def file(self) -> str:
        return f"ep_{self.index:05d}_{Path(self.terrain).stem}.mcap"


def plan_episodes(params: Params) -> list[EpisodePlan]:
    """Episode i gets a terrain drawn from the weighted mix and seed collect.seed * 100_003 + i."""
    cfg = params.collect
    names = sorted(cfg.terrains)
    weights = np.array([cfg.terrains[n] for n in names], dtype=float)
    rng = np.random.default_rng(cfg.seed)
    picks = rng.choice(len(names), size=cfg.episodes, p=weights / weights.sum())
    return [EpisodePlan(i, names[k], cfg.seed * 100_003 + i) for i, k in enumerate(picks)]


def dataset_signature(params: Params) -> str:
    """Hash of everything that changes the episodes' content; a manifest with another signature is stale."""
    return params_hash(params, collect={"workers", "episodes", "out_dir"})


def make_env(params: Params, terrain: str) -> HexapodEnv:
    """A bare env (no observation sensors): the logger reads the sensors on the steps it keeps only."""
    task = params.task.model_copy(update={"sensors": ()})
    return HexapodEnv(terrain, sim=params.sim, cpg=params.cpg, sensors=params.sensors, task=task)


def _rollout(params: Params, plan: EpisodePlan, env: HexapodEnv, log: Any) -> tuple[dict[str, Any], float]:
    """Run the episode; returns the last info and the seconds spent in env.step alone (the bare env's share)."""
    cfg = params.collect
    rng = np.random.default_rng(plan.seed)
    max_steps = round(cfg.max_seconds * params.sim.control_hz)
    info = env.last_info
    env_seconds = 0.0
    log.step(0.0, info, force=True)
    for _ in range(max_steps):
        action = rng.uniform(-cfg.action_scale, cfg.action_scale, size=3)
        tick = time.perf_counter()
        _, reward, terminated, truncated, info = env.step(action)
        env_seconds += time.perf_counter() - tick
        ended = terminated or truncated or env.steps >= max_steps
        log.step(reward, info, force=ended)
        if ended:
            break
    return info, env_seconds


def run_episode(params: Params, plan: EpisodePlan, out_dir: Path) -> dict[str, Any]:
    """Roll out one random-policy episode and log it to out_dir.

    Times the episode twice over: `seconds` in all, `env_seconds` inside env.step only. The difference is what
    logging costs (sensor reads on kept steps, encoding, writing), measured on the very same steps and load.
    """
    from hexpipe.recording.episode import EpisodeLog, episode_metadata

    env = make_env(params, plan.terrain)
    env.reset(seed=plan.seed)
    start = time.perf_counter()
    metadata = episode_metadata(env, plan.seed, params.model_dump_json(), index=plan.index, policy="random")
    with EpisodeLog(env, out_dir / plan.file, metadata, log_every=params.collect.log_every) as log:
        info, env_seconds = _rollout(params, plan, env, log)
    seconds = time.perf_counter() - start
    env.close()
    return {
        **asdict(plan), "file": plan.file, "frames": log.frames, "steps": env.steps,
        "distance": round(info["distance"], 4), "termination": info["termination"] or "time_limit",
        "bytes": (out_dir / plan.file).stat().st_size, "seconds": round(seconds, 4),
        "env_seconds": round(env_seconds, 4),
    }


def read_manifest(out_dir: Path) -> dict[str, Any] | None:
    path = out_dir / MANIFEST
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError:
        return None  # a manifest is only ever replaced atomically; an unreadable one is foreign: start over


def write_manifest(out_dir: Path, signature: str, rows: list[dict[str, Any]]) -> None:
    """Rewrite the manifest atomically; wall-clock timings stay out so the dataset is byte-for-byte reproducible."""
    episodes = [{k: v for k, v in r.items() if k not in TIMINGS} for r in sorted(rows, key=lambda r: r["index"])]
    tmp = out_dir / (MANIFEST + ".tmp")
    tmp.write_text(json.dumps({"signature": signature, "episodes": episodes}, indent=1))
    tmp.replace(out_dir / MANIFEST)


def collect(params: Params, on_episode: Callable[[int, int], None] | None = None) -> dict[str, Any]:
    """Run the missing episodes of the plan in worker processes; returns the collect report."""
    cfg = params.collect
    out_dir = Path(cfg.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    signature = dataset_signature(params)
    plans = plan_episodes(params)
    wanted = {p.file for p in plans}

    manifest = read_manifest(out_dir)
    done: dict[str, dict[str, Any]] = {}
    if manifest is not None and manifest.get("signature") == signature:
        done = {r["file"]: r for r in manifest["episodes"] if r["file"] in wanted and (out_dir / r["file"]).is_file()}
    for stale in out_dir.glob("*.mcap*"):  # other params' episodes, and partial files of a killed run
        if stale.name not in done:
            stale.unlink()
    write_manifest(out_dir, signature, list(done.values()))

    pending = [p for p in plans if p.file not in done]
    ran: list[dict[str, Any]] = []
    if on_episode:
        on_episode(len(done), len(plans))
    with ProcessPoolExecutor(max_workers=cfg.workers, mp_context=get_context("fork")) as pool:
        start = time.perf_counter()
        futures = [pool.submit(run_episode, params, plan, out_dir) for plan in pending]
        try:
            for future in as_completed(futures):
                row = future.result()
                done[row["file"]] = row
                ran.append(row)
                write_manifest(out_dir, signature, list(done.values()))
                if on_episode:
                    on_episode(len(done), len(plans))
        except BaseException:
            for f in futures:
                f.cancel()
            raise
    wall = time.perf_counter() - start
    return collect_report(list(done.values()), ran, wall, cfg.workers)


# throughput of the episodes run now: measured, not results (they go to reports/collect_speed.json)
SPEED_KEYS = ("wall_seconds", "frames_per_s", "env_steps_per_s_per_worker", "bare_env_steps_per_s",
              "logging_rate_vs_bare")


def collect_report(rows: list[dict[str, Any]], ran: list[dict[str, Any]], wall: float, workers: int) -> dict[str, Any]:
    """Dataset figures (all episodes) and throughput (the episodes run now) for reports/collect.json."""
    import pandas as pd

    df = pd.DataFrame(rows)
    report: dict[str, Any] = {
        "episodes": len(df), "frames": int(df["frames"].sum()), "bytes": int(df["bytes"].sum()),
        "env_steps": int(df["steps"].sum()),
        "terrain_mix": {k: int(v) for k, v in df["terrain"].value_counts().sort_index().items()},
        "terminations": {k: int(v) for k, v in df["termination"].value_counts().sort_index().items()},
        "mean_distance_m": round(float(df["distance"].mean()), 4),
    }
    if ran:
        recent = pd.DataFrame(ran)
        per_worker_rate = float(recent["steps"].sum() / recent["seconds"].sum())
        bare_rate = float(recent["steps"].sum() / recent["env_seconds"].sum())
        report.update({
            "episodes_run_now": len(recent), "wall_seconds": round(wall, 2), "workers": workers,
            "frames_per_s": round(float(recent["frames"].sum()) / wall, 2),
            "env_steps_per_s_per_worker": round(per_worker_rate, 2),
            "bare_env_steps_per_s": round(bare_rate, 2),
            "logging_rate_vs_bare": round(per_worker_rate / bare_rate, 4),
        })
    return report
