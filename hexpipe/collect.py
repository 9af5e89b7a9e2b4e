"""The collect stage: random-policy rollouts over a terrain mix, logged to MCAP, with a manifest and a report.

As in the paper, the robot walks "with a random policy": every control step draws a random second derivative of
(a, b, omega) (their rate with `cpg.action_order: 1`) within +-`action_scale`. Episodes are planned up front from
(collect.seed, episode index), so the dataset is reproducible and a rerun after an interruption only runs the
episodes whose files are missing. Each file appears under its final name only when complete (see `EpisodeWriter`),
and the manifest is rewritten atomically after every finished episode: it never lists a file that cannot be read.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, wait
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from hexpipe.config import Params, params_hash
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.paths import safe_name
from hexpipe.recording.manifest import MANIFEST as MANIFEST  # re-exported for callers
from hexpipe.recording.manifest import check_file, file_digest, read_manifest, read_signature, write_manifest
from hexpipe.workers import sigint_flag, stop_pool, worker_pool

TIMINGS = ("seconds", "env_seconds")  # wall-clock figures: reported, never in the (reproducible) manifest


@dataclass(frozen=True)
class EpisodePlan:
    index: int
    terrain: str
    seed: int

    @property
    def file(self) -> str:
        return f"ep_{self.index:05d}_{safe_name(Path(self.terrain).stem, fallback='terrain')}.mcap"


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


def random_gait_params(params: Params) -> Params:
    """The params the random gait walks under: cpg with collect's own bounds and action order, where set."""
    gait = params.collect.gait(params.cpg)
    return params if gait is params.cpg else params.model_copy(update={"cpg": gait})


def make_env(params: Params, terrain: str) -> HexapodEnv:
    """A bare env (no observation sensors): the logger reads the sensors on the steps it keeps only."""
    return HexapodEnv.from_params(params, terrain, obs_sensors=())


def _rollout(params: Params, plan: EpisodePlan, env: HexapodEnv, log: Any) -> tuple[dict[str, Any], float]:
    """Run the episode; returns the last info and the seconds spent in env.step alone (the bare env's share)."""
    cfg = params.collect
    rng = np.random.default_rng(plan.seed)
    max_steps = round(cfg.max_seconds * params.sim.control_hz)
    info = env.last_info
    env_seconds = 0.0
    log.step(0.0, force=True)
    for _ in range(max_steps):
        action = rng.uniform(-cfg.action_scale, cfg.action_scale, size=3)
        tick = time.perf_counter()
        _, reward, terminated, truncated, info = env.step(action)
        env_seconds += time.perf_counter() - tick
        ended = terminated or truncated or env.steps >= max_steps
        log.step(reward, force=ended)
        if ended:
            break
    return info, env_seconds


def run_episode(params: Params, plan: EpisodePlan, out_dir: Path) -> dict[str, Any]:
    """Roll out one random-policy episode and log it to out_dir.

    Times the episode twice over: `seconds` in all, `env_seconds` inside env.step only. The difference is what
    logging costs (sensor reads on kept steps, encoding, writing), measured on the very same steps and load.
    """
    from hexpipe.recording.episode import EpisodeLog, episode_metadata

    walked = random_gait_params(params)  # the params the episode runs under, and logs
    env = make_env(walked, plan.terrain)
    env.reset(seed=plan.seed)
    start = time.perf_counter()
    metadata = episode_metadata(env, plan.seed, walked.model_dump_json(), index=plan.index, policy="random")
    with EpisodeLog(env, out_dir / plan.file, metadata, log_every=params.collect.log_every) as log:
        info, env_seconds = _rollout(params, plan, env, log)
    seconds = time.perf_counter() - start
    env.close()
    return {
        **asdict(plan), "file": plan.file, "frames": log.frames, "steps": env.steps,
        "distance": round(info["distance"], 4), "termination": info["termination"] or "time_limit",
        "bytes": (out_dir / plan.file).stat().st_size, "digest": file_digest(out_dir / plan.file),
        "seconds": round(seconds, 4),
        "env_seconds": round(env_seconds, 4),
    }


def check_manifest(params: Params) -> None:
    """Fail early (ManifestError, one line) on a manifest of the wrong shape in collect.out_dir."""
    out_dir = Path(params.collect.out_dir)
    if read_signature(out_dir) == dataset_signature(params):
        read_manifest(out_dir)


def trusted_episodes(out_dir: Path, signature: str, wanted: set[str], say: Callable[[str], None]) -> dict[str, Any]:
    """The manifest's episodes that belong to this plan and whose files are intact (size and hash), by file name.

    A manifest made under another signature lists nothing usable; a damaged file is dropped, so it is collected
    again; a manifest of the wrong shape is a ManifestError (one line)."""
    if read_signature(out_dir) != signature:
        return {}
    manifest = read_manifest(out_dir)
    done: dict[str, Any] = {}
    if manifest is None:  # removed since its signature was read
        return done
    for row in manifest.episodes:
        if row.file not in wanted:
            continue
        problem = check_file(out_dir, row)
        if problem is None:
            done[row.file] = row.model_dump()
        elif problem != "missing":
            say(f"collect: {out_dir / row.file} is damaged ({problem}); collecting it again")
    return done


def collect(
    params: Params, on_episode: Callable[[int, int], None] | None = None, say: Callable[[str], None] = print,
) -> dict[str, Any]:
    """Run the missing episodes of the plan in worker processes; returns the collect report.

    Ctrl-C (SIGINT) stops at once: queued episodes are cancelled, running ones killed (they leave only temp files),
    and every episode that finished is in the manifest before KeyboardInterrupt is raised."""
    cfg = params.collect
    out_dir = Path(cfg.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    signature = dataset_signature(params)
    plans = plan_episodes(params)
    done = trusted_episodes(out_dir, signature, {p.file for p in plans}, say)
    stale = [p for p in out_dir.glob("*.mcap*") if p.name not in done]  # other params', damaged, partial, foreign
    for path in stale:
        path.unlink()
    if stale:
        say(f"collect: removed {len(stale)} file(s) in {out_dir} that the manifest does not vouch for")
    write_manifest(out_dir, signature, list(done.values()))

    pending = [p for p in plans if p.file not in done]
    ran: list[dict[str, Any]] = []
    if on_episode:
        on_episode(len(done), len(plans))

    def record(row: dict[str, Any]) -> None:
        done[row["file"]] = {k: v for k, v in row.items() if k not in TIMINGS}
        ran.append(row)
        write_manifest(out_dir, signature, list(done.values()))
        if on_episode:
            on_episode(len(done), len(plans))

    start = time.perf_counter()
    with worker_pool(cfg.workers) as pool, sigint_flag() as interrupted:
        futures = {pool.submit(run_episode, params, plan, out_dir) for plan in pending}
        try:
            while futures and not interrupted():
                finished, futures = wait(futures, timeout=0.05, return_when=FIRST_COMPLETED)
                for future in finished:
                    record(future.result())
        except BaseException:
            stop_pool(pool)
            raise
        if interrupted():
            stop_pool(pool)
            for future in futures:  # finished between the last poll and the stop: keep them too
                if future.done() and not future.cancelled() and future.exception() is None:
                    record(future.result())
            for plan in pending:  # a file renamed into place by a worker killed before it reported: unvouched
                if plan.file not in done:
                    (out_dir / plan.file).unlink(missing_ok=True)
            raise KeyboardInterrupt
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
