"""Evaluation outputs: metrics.json, results.csv, grid.csv, figures and report.md, each written atomically.

Figures are drawn on Agg canvases (no display, no pyplot global state): `success.png` (success rate per terrain
and controller) and `cpg_<terrain>.png`, the paper's section 4.2 plot: a, b and omega against forward distance for
the policy's first episode, the terrain's blocks shaded.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from hexpipe.evaluation.episodes import TRACE_COLUMNS, EpisodeResult
from hexpipe.evaluation.metrics import Table

# The paper's generalisation claims, by scenario: (claim, crosses?).
PAPER_CLAIMS = {
    "single_block": ("crosses the block it was trained on", True),
    "extra_blocks": ("crosses extra blocks it never saw", True),
    "wide_block": ("fails on a wider block", False),
}
CROSSES = 0.5  # a success rate at or above this counts as "crosses"


@dataclass
class ReportInputs:
    """Everything report.md shows besides the tables."""

    command: str
    terrains: Sequence[str]  # stems, suite order
    controllers: Sequence[str]  # names, report order
    described: dict[str, str]  # controller -> what it is
    params_summary: dict[str, object]
    grid: pd.DataFrame  # ranked, best first
    best_gait: str
    first_policy_episodes: dict[str, EpisodeResult]  # terrain stem -> the policy's episode 0
    cpg_initial: tuple[float, float, float]
    goal_distance: float
    traces: str = ""  # the CPG traces of every episode (csv.gz)
    videos: dict[str, str] = field(default_factory=dict)  # terrain stem -> path
    mcaps: dict[str, list[str]] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


def atomic_write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def _save(fig, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)


def plot_cpg(result: EpisodeResult, path: Path, initial: tuple[float, float, float], goal: float) -> None:
    """a, b, omega against forward distance, blocks shaded, cpg.initial dotted, the goal dashed."""
    from matplotlib.figure import Figure

    trace = result.trace
    x = trace[:, TRACE_COLUMNS.index("distance")]
    fig = Figure(figsize=(7, 6), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    labels = {"a": "a: stride (rad)", "b": "b: lift (rad)", "omega": "omega (rad/s)"}
    for ax, (key, label), init in zip(axes, labels.items(), initial, strict=True):
        for lo, hi in result.obstacles:
            ax.axvspan(lo, hi, color="tab:brown", alpha=0.25, lw=0)
        ax.plot(x, trace[:, TRACE_COLUMNS.index(key)], color="tab:blue", lw=1.2)
        ax.axhline(init, color="grey", ls=":", lw=1)
        ax.axvline(goal, color="tab:green", ls="--", lw=1)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("forward distance (m)")
    row = result.row
    axes[0].set_title(f"{row['terrain']}: policy, seed {row['seed']}, {row['termination']} at "
                      f"{row['distance']:.2f} m after {row['time']:.1f} s (blocks shaded, cpg.initial dotted)",
                      fontsize=9)
    _save(fig, path)


def plot_success(table: Table, terrains: Sequence[str], controllers: Sequence[str], path: Path) -> None:
    """Grouped bars: success rate per terrain, one bar per controller."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(max(6, 1.6 * len(terrains)), 4), layout="constrained")
    ax = fig.subplots()
    width = 0.8 / max(len(controllers), 1)
    centres = np.arange(len(terrains))
    for k, controller in enumerate(controllers):
        rates = [table.get(t, {}).get(controller, {}).get("success_rate", 0.0) for t in terrains]
        bars = ax.bar(centres + (k - (len(controllers) - 1) / 2) * width, rates, width, label=controller)
        ax.bar_label(bars, labels=[f"{r:.0%}" for r in rates], fontsize=7)
    ax.set_xticks(centres, list(terrains))
    ax.set_ylim(0, 1.12)
    ax.set_ylabel("success rate")
    ax.legend(fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    _save(fig, path)


def _fmt(value: float | None, spec: str = ".2f") -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else format(value, spec)


def _markdown_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def results_table(table: Table, terrains: Sequence[str], controllers: Sequence[str]) -> str:
    header = ("terrain", "controller", "success", "distance (m)", "time to goal (s)", "cost of transport", "fall",
              "stuck", "mean a / b / omega", "b open / near blocks", "episodes")
    rows = []
    for t in terrains:
        for c in controllers:
            m = table.get(t, {}).get(c)
            if m is None:
                continue
            rows.append((
                t, c, _fmt(m["success_rate"], ".0%"), f"{m['distance_mean']:.2f} ± {m['distance_std']:.2f}",
                _fmt(m.get("time_to_goal_mean"), ".1f"), _fmt(m.get("cost_of_transport")), _fmt(m["fall_rate"], ".0%"),
                _fmt(m["stuck_rate"], ".0%"), f"{m['a_mean']:.2f} / {m['b_mean']:.2f} / {m['omega_mean']:.2f}",
                f"{_fmt(m.get('b_open'))} / {_fmt(m.get('b_near_block'))}", str(m["episodes"]),
            ))
    return _markdown_table(header, rows)


def claims_table(table: Table, terrains: Sequence[str]) -> str:
    rows = []
    for terrain in terrains:
        if terrain not in PAPER_CLAIMS or "policy" not in table.get(terrain, {}):
            continue
        claim, crosses = PAPER_CLAIMS[terrain]
        rate = table[terrain]["policy"]["success_rate"]
        ours = rate >= CROSSES
        rows.append((terrain, claim, f"{'crosses' if ours else 'fails'} ({rate:.0%} success)",
                     "yes" if ours == crosses else "**no**"))
    if not rows:
        return "_None of the paper's scenarios (single_block, extra_blocks, wide_block) were evaluated._"
    return _markdown_table(("terrain", "paper: the policy ...", "ours: the policy ...", "agrees"), rows)


def grid_table(grid: pd.DataFrame) -> str:
    rows = [(r.gait, _fmt(r.success_rate, ".0%"), _fmt(r.distance_mean), _fmt(r.time_to_goal_mean, ".1f"),
             _fmt(r.fall_rate, ".0%"), _fmt(r.stuck_rate, ".0%"), str(r.episodes)) for r in grid.itertuples()]
    return _markdown_table(("gait", "success", "distance (m)", "time to goal (s)", "fall", "stuck", "episodes"), rows)


def markdown(table: Table, inputs: ReportInputs) -> str:
    terrains, controllers = inputs.terrains, inputs.controllers
    figures = ["![success rate](success.png)"] + [
        f"![CPG parameters on {t}](cpg_{t}.png)" for t in terrains if t in inputs.first_policy_episodes
    ]
    recordings = [f"- `{t}`: video `{inputs.videos[t]}`" for t in terrains if t in inputs.videos]
    recordings += [f"- `{t}`: MCAP " + ", ".join(f"`{p}`" for p in inputs.mcaps[t]) for t in terrains
                   if inputs.mcaps.get(t)]
    if inputs.traces:
        recordings.append(f"- a, b, omega against time and distance, every step of every episode: `{inputs.traces}`")
    settings = "\n".join(f"- {k}: {v}" for k, v in inputs.params_summary.items())
    parts = [
        "# Evaluation",
        f"Produced by:\n\n```\n{inputs.command}\n```",
        "Every controller runs the same seeded episodes on every terrain (domain randomisation off).\n\n"
        + "\n".join(f"- `{c}`: {inputs.described.get(c, '')}" for c in controllers) + f"\n\n{settings}",
        "## Results\n\n" + results_table(table, terrains, controllers) + "\n\nCost of transport: E / (m g d) of the "
        "episodes that reach the goal, E the mechanical work of the 18 joints (sum of |torque x velocity| over time). "
        "b open / near blocks: the mean lift (rad) on open ground and from 1 m before a block to 0.5 m past it; an "
        "adaptive gait lifts near blocks only.",
        "## The paper's claims and ours\n\nThe policy \"crosses\" a terrain when at least "
        f"{CROSSES:.0%} of its episodes reach the goal.\n\n" + claims_table(table, terrains),
        f"## Best fixed gait\n\n`best_fixed` = **{inputs.best_gait}** (zero action: the CPG holds it), the best of "
        "the grid below on the training terrains (ranked by success rate, then mean distance up to the goal, then "
        "time to goal; "
        "seeds disjoint from the evaluation seeds).\n\n" + grid_table(inputs.grid),
        "## Figures\n\nThe CPG plots show the policy's first episode on each terrain: a, b and omega against forward "
        "distance with the blocks (and bumpy ground) shaded (the paper, section 4.2: a grows for long strides, b "
        "rises before a block).\n\n" + "\n\n".join(figures),
    ]
    if recordings:
        parts.append("## Recordings\n\n" + "\n".join(recordings))
    if inputs.notes:
        parts.append("## Notes\n\n" + "\n".join(f"- {n}" for n in inputs.notes))
    return "\n\n".join(parts) + "\n"


def write_reports(report_dir: Path, rows: pd.DataFrame, table: Table, inputs: ReportInputs) -> list[Path]:
    """Write every report file (metrics.json last, so its presence means the rest is complete)."""
    report_dir.mkdir(parents=True, exist_ok=True)
    written = []
    atomic_write(report_dir / "results.csv", rows.to_csv(index=False))
    atomic_write(report_dir / "grid.csv", inputs.grid.to_csv(index=False))
    written += [report_dir / "results.csv", report_dir / "grid.csv"]
    plot_success(table, inputs.terrains, inputs.controllers, report_dir / "success.png")
    written.append(report_dir / "success.png")
    for stale in report_dir.glob("cpg_*.png"):  # terrains of an earlier run
        if stale.stem.removeprefix("cpg_") not in inputs.first_policy_episodes:
            stale.unlink()
    for terrain, result in inputs.first_policy_episodes.items():
        path = report_dir / f"cpg_{terrain}.png"
        plot_cpg(result, path, inputs.cpg_initial, inputs.goal_distance)
        written.append(path)
    atomic_write(report_dir / "report.md", markdown(table, inputs))
    atomic_write(report_dir / "metrics.json", json.dumps(table, indent=2) + "\n")
    return [*written, report_dir / "report.md", report_dir / "metrics.json"]
