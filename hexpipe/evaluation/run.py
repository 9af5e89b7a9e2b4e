"""The evaluate stage: every controller on every terrain of the suite, on the same seeded episodes.

Order of work, as data (`Plan`): validate everything that can be wrong (terrains, grid, policies) before any
episode runs; run the fixed-gait grid on the training terrains and, in the same worker pool, the learned and
open-loop controllers on the suite; once the grid is done, pick `best_fixed` (`Choice`) and run it on the suite
too (`run_plan`). Episode i of every (terrain,
controller) uses seed eval.seed + i; the grid uses the next GRID_SEEDS seeds, so the baseline is not chosen on
the very episodes it is then scored on. Outputs go to eval.out_dir (MCAP logs, videos, CPG traces) and
eval.report_dir (metrics.json, results.csv, grid.csv, report.md, figures), every file via a temporary name.
"""

from __future__ import annotations

import json
import math
import shlex
import sys
import time
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Future, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from hexpipe.atomic import atomic_path
from hexpipe.config import Params
from hexpipe.evaluation.controllers import (
    GRID,
    ORDER,
    ControllerSpec,
    Gait,
    gait_label,
    grid_gaits,
    learned_controllers,
)
from hexpipe.evaluation.episodes import TRACE_COLUMNS, EpisodeJob, EpisodeResult, run_episode
from hexpipe.evaluation.metrics import Table, rank_gaits, summarise
from hexpipe.evaluation.report import ReportInputs, write_reports
from hexpipe.evaluation.suite import Scenario, evaluation_suite, training_suite
from hexpipe.paths import inside
from hexpipe.workers import worker_pool

GRID_SEEDS = 3  # episodes per gait and training terrain in the best_fixed search
TRACES = "cpg_traces.csv.gz"
# Param sections evaluate reads (as dvc.yaml lists them); the reconstructed command overrides only these.
_READS = ("sim", "cpg", "sensors", "task", "eval", "ppo.train_terrains", "collect.log_every")


@dataclass(frozen=True)
class Plan:
    """What evaluate runs, validated before any episode: the suite, the training terrains and gaits of the grid, and
    the controllers with their descriptions. Two phases: `first_jobs` (the grid and every controller but best_fixed,
    all at once), then, once the grid is done, `best_fixed_jobs` of the gait it chose."""

    suite: list[Scenario]
    train: list[Scenario]
    gaits: list[Gait]
    learned: list[ControllerSpec]
    described: dict[str, str]  # controller -> what it is
    notes: list[str]
    extra_terrains: tuple[str, ...]

    def first_jobs(self, params: Params) -> list[EpisodeJob]:
        """The grid on the training terrains, the learned and open-loop controllers on the suite; slow filmed or
        logged episodes first."""
        jobs = _grid_jobs(params, self.train, self.gaits)
        for spec in [*self.learned, *_reflex_gait(params), ControllerSpec("open_loop", gait=params.cpg.initial)]:
            jobs += _suite_jobs(params, self.suite, spec)
        jobs.sort(key=lambda j: (j.video is None, j.mcap is None))
        return jobs

    def best_fixed_jobs(self, params: Params, choice: Choice) -> list[EpisodeJob]:
        return _suite_jobs(params, self.suite, ControllerSpec("best_fixed", gait=choice.gait))

    def episodes(self, params: Params) -> int:
        """Every episode of both phases (for the progress bar)."""
        grid = len(self.gaits) * len(self.train) * GRID_SEEDS
        controllers = len(self.learned) + len(_reflex_gait(params)) + 2  # + open_loop, best_fixed
        return grid + controllers * len(self.suite) * params.eval.episodes


def _reflex_gait(params: Params) -> list[ControllerSpec]:
    """The `reflex_gait` baseline, when eval.reflex_gait names its gait."""
    gait = params.eval.reflex_gait
    return [] if gait is None else [ControllerSpec("reflex_gait", gait=gait, lift_reflex=True)]


@dataclass(frozen=True)
class Choice:
    """The best fixed gait and the grid's ranking it came from (best first)."""

    gait: Gait
    ranking: pd.DataFrame


@dataclass(frozen=True)
class Outcome:
    results: list[EpisodeResult]  # both phases, in completion order
    choice: Choice
    wall: float  # s

    @property
    def evaluated(self) -> list[EpisodeResult]:
        """The suite's episodes (the grid's left out)."""
        return [r for r in self.results if r.job.controller.name != GRID]

    @property
    def written(self) -> set[Path]:
        """The MCAP logs and videos this run wrote."""
        return {p for r in self.evaluated for p in (r.job.mcap, r.job.video) if p is not None}

    @property
    def controllers(self) -> list[str]:
        return [c for c in ORDER if any(r.job.controller.name == c for r in self.results)]


def plan(params: Params, extra_terrains: tuple[str, ...]) -> Plan:
    """Everything that can be wrong, checked before any episode runs: TerrainError, ConfigError, PolicyError."""
    suite = evaluation_suite(params, extra_terrains)
    train = training_suite(params)
    gaits = grid_gaits(params)
    learned, described, notes = learned_controllers(params)
    return Plan(suite, train, gaits, learned, described, notes, extra_terrains)


def _suite_jobs(params: Params, suite: list[Scenario], spec: ControllerSpec) -> list[EpisodeJob]:
    """eval.episodes jobs per terrain; the policy's first episodes are logged to MCAP and its first one filmed."""
    cfg, out = params.eval, Path(params.eval.out_dir)
    jobs = []
    for scenario in suite:
        for i in range(cfg.episodes):
            learned = spec.name == "policy"
            mcap = out / scenario.stem / f"ep_{i}.mcap" if learned and i < cfg.log_episodes else None
            video = out / f"{scenario.stem}.mp4" if learned and i == 0 and cfg.record_video else None
            jobs.append(EpisodeJob(scenario, spec, i, cfg.seed + i, mcap=mcap, video=video))
    return jobs


def _grid_jobs(params: Params, train: list[Scenario], gaits: list[Gait]) -> list[EpisodeJob]:
    first = params.eval.seed + params.eval.episodes  # disjoint from the evaluation seeds
    return [EpisodeJob(s, ControllerSpec(GRID, gait=g), i, first + i) for g in gaits for s in train
            for i in range(GRID_SEEDS)]


def choose_best_fixed(grid: list[EpisodeResult], goal_distance: float) -> Choice:
    ranked = rank_gaits(pd.DataFrame([r.row for r in grid]), goal_distance)
    gaits = {gait_label(r.job.controller.gait): r.job.controller.gait for r in grid}
    return Choice(gaits[ranked.iloc[0]["gait"]], ranked)


def run_plan(params: Params, work: Plan, progress: Callable[[], None]) -> Outcome:
    """Run both phases in one worker pool: the first phase's jobs at once, best_fixed's as soon as the last grid
    episode is in (while the rest of the first phase still runs)."""
    started = time.perf_counter()
    jobs = work.first_jobs(params)
    results: list[EpisodeResult] = []
    choice: Choice | None = None
    grid_left = sum(j.controller.name == GRID for j in jobs)
    with worker_pool(params.eval.workers, ignore_sigint=False) as pool:  # workers die with a killed evaluate
        pending: dict[Future, EpisodeJob] = {pool.submit(run_episode, params, j): j for j in jobs}
        try:
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in done:
                    job = pending.pop(future)
                    results.append(future.result())
                    progress()
                    if job.controller.name == GRID:
                        grid_left -= 1
                        if grid_left == 0:  # phase 2
                            grid = [r for r in results if r.job.controller.name == GRID]
                            choice = choose_best_fixed(grid, params.task.goal_distance)
                            more = work.best_fixed_jobs(params, choice)
                            pending |= {pool.submit(run_episode, params, j): j for j in more}
        except BaseException:
            for future in pending:
                future.cancel()
            raise
    assert choice is not None  # the grid has at least one gait and one training terrain
    return Outcome(results, choice, time.perf_counter() - started)


def _same(a: Any, b: Any) -> bool:
    """Equal, floats to 1e-6 relative (params.yaml rounds the pi-derived defaults)."""
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float | int) and isinstance(b, float | int) and not isinstance(a, bool):
        return math.isclose(a, b, rel_tol=1e-6)
    return a == b


def _overrides(params: Params) -> list[str]:
    """--set overrides, vs the code defaults (= params.yaml), of every param evaluate reads."""
    now, default = params.model_dump(mode="json"), Params().model_dump(mode="json")
    out = []
    for key in _READS:
        section, _, field = key.partition(".")
        names = [field] if field else list(now[section])
        for name in names:
            value = now[section][name]
            if isinstance(value, dict):  # a nested section: task.randomization
                out += [f"{section}.{name}.{k}={json.dumps(v)}" for k, v in value.items()
                        if not _same(v, default[section][name][k])]
            elif not _same(value, default[section][name]):
                out.append(f"{section}.{name}={value if isinstance(value, str) else json.dumps(value)}")
    return out


def command_line(params: Params, extra_terrains: Iterable[str]) -> str:
    """The command that reproduces this run: the CLI's own argv when run from it, else an equivalent one."""
    argv = sys.argv
    if Path(argv[0]).name in ("hexpipe", "cli.py") and "evaluate" in argv[1:]:
        return shlex.join(["hexpipe", *argv[1:]])
    args = ["hexpipe", "evaluate"]
    for override in _overrides(params):
        args += ["--set", override]
    for terrain in extra_terrains:
        args += ["--terrain", terrain]
    return shlex.join(args) + "  # equivalent: evaluate() was called from Python"


def _remove_stale(out_dir: Path, suite: list[Scenario], written: set[Path]) -> None:
    """Drop this suite's recordings that an earlier run left and this one did not rewrite (only inside out_dir)."""
    for scenario in suite:
        old = [*(out_dir / scenario.stem).glob("ep_*.mcap"), out_dir / f"{scenario.stem}.mp4"]
        for path in old:
            if path.is_file() and path not in written and inside(path, out_dir):
                path.unlink()


def _write_traces(path: Path, results: list[EpisodeResult]) -> None:
    frames = []
    for r in results:
        df = pd.DataFrame(r.trace, columns=list(TRACE_COLUMNS))
        df.insert(0, "episode", r.row["episode"])
        df.insert(0, "controller", r.row["controller"])
        df.insert(0, "terrain", r.row["terrain"])
        frames.append(df)
    with atomic_path(path) as tmp:  # the temp name keeps .gz, but compression is given, not inferred
        pd.concat(frames, ignore_index=True).to_csv(tmp, index=False, float_format="%.5g", compression="gzip")


def _ranks(names: Iterable[str]) -> dict[str, int]:
    return {name: i for i, name in enumerate(dict.fromkeys(names))}


def _progress_bar(total: int, show: bool) -> tuple[Any, Callable[[], None]]:
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn, TimeRemainingColumn

    bar = Progress("[bold]evaluate", BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(), TimeRemainingColumn(),
                   console=Console(stderr=True), disable=not show)
    task = bar.add_task("episodes", total=total)
    return bar, lambda: bar.advance(task)


def evaluate(params: Params, extra_terrains: Iterable[str] = (), show_progress: bool = True) -> str:
    """Run the suite, write the reports, and return a short printable summary."""
    work = plan(params, tuple(extra_terrains))
    out_dir, report_dir = Path(params.eval.out_dir), Path(params.eval.report_dir)
    out_dir.mkdir(parents=True, exist_ok=True)

    bar, advance = _progress_bar(work.episodes(params), show_progress)
    with bar:
        outcome = run_plan(params, work, advance)

    terrains = [s.stem for s in work.suite]
    order = {"terrain": _ranks([*terrains, *(s.stem for s in work.train)]), "controller": _ranks([*ORDER, GRID])}
    rows = pd.DataFrame([r.row for r in outcome.results]).sort_values(  # grid rows: one per gait, hence `gait`
        ["terrain", "controller", "episode", "gait"], key=lambda col: col.map(order[col.name]) if col.name in order
        else col, kind="stable")
    table = summarise(rows, terrains, outcome.controllers)
    _remove_stale(out_dir, work.suite, outcome.written)
    _write_traces(out_dir / TRACES, outcome.evaluated)

    inputs = _report_inputs(params, work, outcome)
    write_reports(report_dir, rows, table, inputs)
    return _summary(table, terrains, outcome.controllers, inputs.best_gait, outcome.wall, report_dir)


def _report_inputs(params: Params, work: Plan, outcome: Outcome) -> ReportInputs:
    cfg, out_dir = params.eval, Path(params.eval.out_dir)
    terrains, written, gait = [s.stem for s in work.suite], outcome.written, outcome.choice.gait
    first = {r.row["terrain"]: r for r in outcome.evaluated if r.job.controller.name == "policy" and r.job.index == 0}
    return ReportInputs(
        command=command_line(params, work.extra_terrains), terrains=terrains, controllers=outcome.controllers,
        described={**work.described, "best_fixed": f"fixed gait {gait_label(gait)} (zero action)",
                   "open_loop": f"fixed gait {gait_label(params.cpg.initial)} = cpg.initial (zero action)",
                   **({"reflex_gait": f"fixed gait {gait_label(cfg.reflex_gait)} with the lift reflex moving the legs "
                                      "(task.lift_reflex)"} if cfg.reflex_gait else {})},
        params_summary={
            "episodes per terrain and controller": cfg.episodes, "seeds": f"{cfg.seed}..{cfg.seed + cfg.episodes - 1}",
            "goal": f"{params.task.goal_distance} m", "time limit": f"{params.task.time_limit} s",
            "best_fixed search": f"{len(work.gaits) * len(work.train)} (gait, training terrain) pairs x "
                                 f"{GRID_SEEDS} seeds",
            "wall time": f"{outcome.wall:.0f} s with {cfg.workers} workers",
        },
        grid=outcome.choice.ranking, best_gait=gait_label(gait), first_policy_episodes=first,
        cpg_initial=params.cpg.initial, goal_distance=params.task.goal_distance,
        traces=str(out_dir / TRACES), videos={s: str(p) for s in terrains if (p := out_dir / f"{s}.mp4") in written},
        mcaps={s: sorted(str(p) for p in written if p.suffix == ".mcap" and p.parent.name == s) for s in terrains},
        notes=work.notes,
    )


def _summary(
    table: Table, terrains: list[str], controllers: list[str], best: str, wall: float, report_dir: Path
) -> str:
    width = max(len(t) for t in terrains)
    lines = [f"evaluate: {len(terrains)} terrains x {len(controllers)} controllers in {wall:.0f} s",
             f"best fixed gait: {best}", f"{'success':{width}s}  " + "  ".join(f"{c:>10s}" for c in controllers)]
    for t in terrains:
        cells = [f"{table[t][c]['success_rate']:>10.0%}" if c in table.get(t, {}) else f"{'-':>10s}"
                 for c in controllers]
        lines.append(f"{t:{width}s}  " + "  ".join(cells))
    lines.append(f"report: {report_dir / 'report.md'}")
    return "\n".join(lines)
