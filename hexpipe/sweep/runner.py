"""Run the sweep's trials as Ray tasks: a local cluster by default, or the one at --address / RAY_ADDRESS.

Ray does the scheduling: each trial is one task that reserves `Trial.cpus` CPUs, so a node runs as many trials at
once as its CPUs allow. The driver only submits, waits, and writes each record the moment its task returns
(store.py), so a rerun after Ctrl-C or kill -9 submits only the trials that have no complete record.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hexpipe.config import ConfigError, Params
from hexpipe.sweep.grid import Trial
from hexpipe.sweep.store import load_result, save_failure, save_result
from hexpipe.sweep.trial import run_trial


@dataclass
class Outcome:
    """What a run of the sweep found and did; `results` holds every complete trial's record, old and new."""

    results: dict[str, dict[str, Any]] = field(default_factory=dict)
    failures: dict[str, dict[str, Any]] = field(default_factory=dict)
    skipped: list[str] = field(default_factory=list)
    ran: list[str] = field(default_factory=list)
    wall: float = 0.0
    cluster_cpus: float = 0.0
    nodes: int = 0


def eta_seconds(trial_seconds: list[float], left: int, slots: int) -> float | None:
    """Rough time to finish `left` trials (queued or running) at `slots` at a time, from the mean trial time."""
    if not trial_seconds or left <= 0:
        return None if left > 0 else 0.0
    return sum(trial_seconds) / len(trial_seconds) * math.ceil(left / max(slots, 1))


def format_seconds(seconds: float | None) -> str:
    if seconds is None:
        return "?"
    minutes, secs = divmod(round(seconds), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


def _connect(address: str | None, cpus: int) -> bool:
    """ray.init on a cluster (address) or a new local one; True if this call started Ray (so shuts it down)."""
    if not address:
        # A local cluster serves this machine only: with this set before Ray is imported, Ray binds its servers and
        # the node's address to 127.0.0.1 instead of the machine's network address (Ray's switch for macOS/Windows,
        # where clusters are off: on Linux it is the one that keeps a single-machine Ray off the network).
        os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
    import ray

    if ray.is_initialized():
        return False
    options: dict[str, Any] = {"log_to_driver": False, "logging_level": logging.WARNING}
    if address:
        ray.init(address=address, **options)
    else:
        ray.init(num_cpus=cpus or os.cpu_count() or 1, include_dashboard=False, **options)
    return True


def _error_line(exc: BaseException) -> tuple[str, str]:
    """(one line naming the error, the full text) of a task's failure."""
    import ray.exceptions

    cause = exc.cause if isinstance(exc, ray.exceptions.RayTaskError) and exc.cause is not None else exc
    first = str(cause).strip().splitlines()[0] if str(cause).strip() else ""
    return f"{type(cause).__name__}: {first}"[:500], str(exc)[-8000:]


def run_trials(
    params: Params, trials: list[Trial], address: str | None = None, cpus: int = 0, root: Path | None = None,
    show_progress: bool = True, log: Callable[[str], None] = print,
) -> Outcome:
    """Run every trial without a complete record on Ray; record each result or failure as it arrives."""
    out = Outcome()
    pending = []
    for trial in trials:
        record = load_result(params, trial)
        if record is None:
            pending.append(trial)
        else:
            out.results[trial.name] = record
            out.skipped.append(trial.name)
    if out.skipped:
        log(f"sweep: {len(out.skipped)} of {len(trials)} trials already complete, skipped")
    if not pending:
        return out

    started = time.perf_counter()
    owns = _connect(address or os.environ.get("RAY_ADDRESS"), cpus)
    import ray

    refs: dict[Any, Trial] = {}
    try:
        total_cpus = float(ray.cluster_resources().get("CPU", 0))
        out.cluster_cpus, out.nodes = total_cpus, sum(1 for n in ray.nodes() if n.get("Alive"))
        biggest = max(t.cpus for t in pending)
        if biggest > total_cpus:
            raise ConfigError(f"a trial reserves {biggest} CPUs (max of ppo.n_envs, eval.workers) but the Ray cluster "
                              f"has {total_cpus:g}: lower them or raise --cpus")
        log(f"sweep: {len(pending)} trials on Ray ({out.nodes} node(s), {total_cpus:g} CPUs, "
            f"{biggest} CPUs per trial)")
        task = ray.remote(run_trial)
        for trial in pending:
            ref = task.options(num_cpus=trial.cpus, max_retries=0, name=trial.name).remote(
                trial.params, str(root or Path.cwd()))
            refs[ref] = trial
        _wait_all(params, refs, out, total_cpus, len(trials), show_progress, log)
    except BaseException:
        for ref in refs:  # Ctrl-C or an error: stop the trials still queued or running
            with contextlib.suppress(Exception):
                ray.cancel(ref, force=True)
        raise
    finally:
        out.wall = time.perf_counter() - started
        if owns:
            ray.shutdown()
    return out


def _wait_all(
    params: Params, refs: dict[Any, Trial], out: Outcome, total_cpus: float, n_trials: int, show_progress: bool,
    log: Callable[[str], None],
) -> None:
    import ray
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    per_trial = max(t.cpus for t in refs.values())
    slots = max(int(total_cpus // per_trial), 1)
    seconds: list[float] = []
    bar = Progress("[bold]sweep", BarColumn(), MofNCompleteColumn(), TextColumn("{task.fields[state]}"),
                   TimeElapsedColumn(), console=Console(stderr=True), disable=not show_progress)
    job = bar.add_task("trials", total=n_trials, completed=len(out.skipped), state="")

    def say(text: str) -> None:  # above the live progress bar, not through it
        if show_progress:
            bar.console.print(text, highlight=False, markup=False, soft_wrap=True)
        else:
            log(text)

    with bar:
        while refs:
            done, _ = ray.wait(list(refs), num_returns=1, timeout=1.0)
            for ref in done:
                trial = refs.pop(ref)
                try:
                    record = ray.get(ref)
                except Exception as exc:  # the trial failed: record it, the others go on
                    error, details = _error_line(exc)
                    out.failures[trial.name] = save_failure(params, trial, error, details)
                    say(f"sweep: {trial.name} failed: {error}")
                else:
                    record = {"trial": trial.name, "condition": trial.condition, "seed": trial.seed,
                              "overrides": list(trial.overrides), **record}
                    save_result(params, trial, record)
                    out.results[trial.name] = record
                    out.ran.append(trial.name)
                    seconds.append(record["seconds"]["total"])
                    say(f"sweep: {trial.name} done in {format_seconds(record['seconds']['total'])}")
            free = float(ray.available_resources().get("CPU", 0))
            running = min(len(refs), max(0, round((total_cpus - free) / per_trial)))
            state = (f"{running} running, {len(out.failures)} failed, "
                     f"ETA {format_seconds(eta_seconds(seconds, len(refs), slots))}")
            bar.update(job, completed=len(out.skipped) + len(out.ran) + len(out.failures), state=state)
