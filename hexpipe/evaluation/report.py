"""Evaluation outputs: metrics.json, results.csv, grid.csv, figures and report.md, each written atomically.

Figures are drawn on Agg canvases (no display, no pyplot global state): `success.png` (success rate per terrain
and controller) and `cpg_<terrain>.png`, the paper's section 4.2 plot: a, b and omega against forward distance for
the policy's first episode, the terrain's blocks shaded.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from hexpipe.atomic import atomic_path, write_text
from hexpipe.evaluation.episodes import (
    BEFORE_FACE,
    FOOT_BEFORE_FACE,
    FOOT_ON_EDGE,
    NEAR_AFTER,
    NEAR_BEFORE,
    TRACE_COLUMNS,
    EpisodeResult,
)
from hexpipe.evaluation.metrics import (
    ADAPTATION_TARGET,
    ANYWHERE,
    SUCCESS_MARGIN,
    Table,
    adaptation,
    stall_counts,
    summary_numbers,
    verdict,
)

# The paper's generalisation claims, by scenario: (claim, crosses?).
PAPER_CLAIMS = {
    "single_block": ("crosses the block it was trained on", True),
    "extra_blocks": ("crosses extra blocks it never saw", True),
    "wide_block": ("fails on a wider block", False),
}
CROSSES = 0.5  # a success rate at or above this counts as "crosses"
LEARNED = ("policy", "blind")  # the controllers the verdict judges


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


def _save(fig, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)


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


def _has_feet(result: EpisodeResult | None) -> bool:
    return result is not None and result.feet is not None and len(result.feet) > 0


def plot_gait(result: EpisodeResult, path: Path) -> None:
    """The gait diagram: stance (dark) and swing (light) of every leg against time, with each leg's duty factor."""
    from matplotlib.figure import Figure

    feet = result.feet
    t = result.trace[:, TRACE_COLUMNS.index("time")]
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    fig = Figure(figsize=(10, 2.8), layout="constrained")
    ax = fig.subplots()
    ax.imshow(feet.T, aspect="auto", cmap="Greys", vmin=0, vmax=1.25, interpolation="nearest",
              extent=(t[0] - dt / 2, t[-1] + dt / 2, feet.shape[1] + 0.5, 0.5))
    ax.set_yticks(range(1, feet.shape[1] + 1), [f"leg {k} ({feet[:, k - 1].mean():.0%})"
                                                 for k in range(1, feet.shape[1] + 1)])
    ax.set_xlabel("time (s)")
    row = result.row
    ax.set_title(f"{row['terrain']}: policy, seed {row['seed']}: feet on the ground (dark: stance; duty factor in "
                 "brackets; legs 1/2 front, 3/4 middle, 5/6 back, odd left)", fontsize=9)
    _save(fig, path)


def plot_success(table: Table, terrains: Sequence[str], controllers: Sequence[str], path: Path) -> None:
    """Grouped bars: success rate per terrain, one bar per controller, with its 95% Wilson interval."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(min(12, max(6, 1.2 * len(terrains))), 4), layout="constrained")
    ax = fig.subplots()
    width = 0.8 / max(len(controllers), 1)
    centres = np.arange(len(terrains))
    for k, controller in enumerate(controllers):
        cells = [table.get(t, {}).get(controller, {}) for t in terrains]
        rates = [m.get("success_rate", 0.0) for m in cells]
        errors = [[r - m.get("success_ci_low", r) for r, m in zip(rates, cells, strict=True)],
                  [m.get("success_ci_high", r) - r for r, m in zip(rates, cells, strict=True)]]
        bars = ax.bar(centres + (k - (len(controllers) - 1) / 2) * width, rates, width, label=controller,
                      yerr=errors, error_kw={"elinewidth": 0.8, "capsize": 2, "ecolor": "0.3"})
        ax.bar_label(bars, labels=[f"{r:.0%}" for r in rates], fontsize=7)
    tilt = len(terrains) > 6  # long suites: slanted names do not overlap
    ax.set_xticks(centres, list(terrains), rotation=30 if tilt else 0, ha="right" if tilt else "center")
    ax.set_ylim(0, 1.15)
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


def _spread(m: dict, key: str, prefix: str, spec: str) -> str:
    """'mean ± std (CI low-high)', or '-' where no episode reached the goal."""
    if key not in m:
        return "-"
    return (f"{m[key]:{spec}} ± {m[f'{prefix}_std']:{spec}} ({m[f'{prefix}_ci_low']:{spec}}-"
            f"{m[f'{prefix}_ci_high']:{spec}})")


def results_table(table: Table, terrains: Sequence[str], controllers: Sequence[str]) -> str:
    header = ("terrain", "controller", "success (95% CI)", "distance (m)", "time to goal (s)", "cost of transport",
              "fall", "stuck", "mean a / b / omega", "b before face / open", "episodes")
    rows = []
    for t in terrains:
        for c in controllers:
            m = table.get(t, {}).get(c)
            if m is None:
                continue
            rows.append((
                t, c, f"{m['success_rate']:.0%} ({m['success_ci_low']:.0%}-{m['success_ci_high']:.0%})",
                f"{m['distance_mean']:.2f} ± {m['distance_std']:.2f}",
                _spread(m, "time_to_goal_mean", "time_to_goal", ".1f"),
                _spread(m, "cost_of_transport", "cost_of_transport", ".2f"),
                _fmt(m["fall_rate"], ".0%"), _fmt(m["stuck_rate"], ".0%"),
                f"{m['a_mean']:.2f} / {m['b_mean']:.2f} / {m['omega_mean']:.2f}",
                f"{_fmt(m.get('b_before_block'))} / {_fmt(m.get('b_open'))}", str(m["episodes"]),
            ))
    return _markdown_table(header, rows)


def _mark(ok: bool) -> str:
    return "yes" if ok else "**no**"


def verdict_table(table: Table, terrains: Sequence[str], learned: str, baseline: str = "best_fixed") -> str:
    """Per terrain: the learned controller's and the baseline's figures, and which criteria it meets."""
    calls = verdict(table, terrains, learned, baseline)
    if not calls:
        return f"_`{learned}` and `{baseline}` share no terrain._"
    rows = []
    for v in calls:
        ours, theirs = table[v.terrain][learned], table[v.terrain][baseline]
        rows.append((
            v.terrain, f"{ours['success_rate']:.0%} vs {theirs['success_rate']:.0%}: {_mark(v.success)}",
            f"{_fmt(ours.get('time_to_goal_mean'), '.1f')} vs {_fmt(theirs.get('time_to_goal_mean'), '.1f')}: "
            f"{_mark(v.time)}",
            f"{_fmt(ours.get('cost_of_transport'))} vs {_fmt(theirs.get('cost_of_transport'))}: "
            f"{_mark(v.cost_of_transport)}",
            "**yes**" if v.beats else "no",
        ))
    beaten = sum(v.beats for v in calls)
    what = "the best fixed gait" if baseline == "best_fixed" else f"`{baseline}`"
    overall = (f"**Overall: {'yes' if beaten == len(calls) else 'no'}**: `{learned}` beats {what} on "
               f"{beaten} of {len(calls)} terrains.")
    header = ("terrain", "success", "time to goal (s)", "cost of transport", f"`{learned}` beats it")
    return _markdown_table(header, rows) + "\n\n" + overall


def adaptation_text(table: Table, learned: str) -> str:
    """Issue 10's adaptation and 'any block, anywhere' measures, with their targets."""
    numbers = adaptation(table, learned)
    lines = []
    if "lift_before_face" in numbers:
        lines.append(
            f"- Adaptation, on single_block: mean swing lift (b, or the lift reflex's where higher) "
            f"{numbers['b_before_face']:.2f} rad in the {BEFORE_FACE} m before "
            f"the face, {numbers['b_open']:.2f} rad on open ground: difference {numbers['lift_before_face']:+.2f} rad "
            f"(target >= +{ADAPTATION_TARGET:.2f}): {_mark(bool(numbers['lift_target_met']))}.")
    else:
        lines.append("- Adaptation: not measured (single_block not evaluated, or no episode reached the face).")
    home = table.get("single_block", {}).get(learned)
    moved = [t for t in ANYWHERE if f"{t}_minus_single_block" in numbers]
    if home is not None and moved:
        cells = ", ".join(f"{t} {table[t][learned]['success_rate']:.0%} "
                          f"({numbers[f'{t}_minus_single_block'] * 100:+.0f} points)" for t in moved)
        lines.append(f"- Any block, anywhere: success {cells} against {home['success_rate']:.0%} on single_block "
                     f"(target: none more than {SUCCESS_MARGIN * 100:.0f} points below): "
                     f"{_mark(bool(numbers['anywhere_target_met']))}.")
    return "\n".join(lines)


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
    rows = [(r.gait, _fmt(r.success_rate, ".0%"), _fmt(r.cost_of_transport), _fmt(r.distance_mean),
             _fmt(r.time_to_goal_mean, ".1f"), _fmt(r.fall_rate, ".0%"), _fmt(r.stuck_rate, ".0%"), str(r.episodes))
            for r in grid.itertuples()]
    header = ("gait", "success", "cost of transport", "distance (m)", "time to goal (s)", "fall", "stuck", "episodes")
    return _markdown_table(header, rows)


def stall_table(rows: pd.DataFrame, order: dict[str, Sequence[str]]) -> str:
    """Markdown of `stall_counts`: one line per terrain and controller (say) with stuck or fallen episodes."""
    lines = stall_counts(rows, order)
    if not lines:
        return "Every episode reached the goal or the time limit."
    return _markdown_table((*order, "stuck or fallen", "legs with a foot at a block face"),
                           [(*(f"`{k}`" for k in key), str(n), legs) for key, n, legs in lines])


def verdict_section(table: Table, inputs: ReportInputs) -> str:
    """How to read the verdict, then one table and the adaptation measures per learned controller."""
    parts = [
        f"On each terrain a learned controller beats `best_fixed` when its success rate is at most "
        f"{SUCCESS_MARGIN * 100:.0f} points below (or above), its mean time to goal is no longer and its mean cost of "
        "transport is lower, all three; a controller that never reaches the goal fails the last two, a baseline that "
        "never does passes them. The calls use the point estimates: where the intervals in Results overlap, a call "
        "may flip with other seeds.",
    ]
    for learned in (c for c in LEARNED if c in inputs.controllers):
        parts += [f"### `{learned}`", verdict_table(table, inputs.terrains, learned), adaptation_text(table, learned)]
        if "reflex_gait" in inputs.controllers:
            parts += ["Against `reflex_gait`, the fixed gait with the lift reflex moving its legs (adaptation by "
                      "hand), on the same criteria:", verdict_table(table, inputs.terrains, learned, "reflex_gait")]
    return "\n\n".join(parts)


def markdown(table: Table, inputs: ReportInputs, rows: pd.DataFrame) -> str:
    terrains, controllers = inputs.terrains, inputs.controllers
    figures = ["![success rate](success.png)"] + [
        f"![CPG parameters on {t}](cpg_{t}.png)" for t in terrains if t in inputs.first_policy_episodes
    ] + [f"![gait diagram on {t}](gait_{t}.png)" for t in terrains if _has_feet(inputs.first_policy_episodes.get(t))]
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
        "## Results\n\n" + results_table(table, terrains, controllers) + "\n\nSuccess: the share of episodes that "
        "reach the goal, with its 95% Wilson interval. Time to goal and cost of transport: mean ± std (95% bootstrap "
        "interval of the mean) over the episodes that reach the goal. Cost of transport: E / (m g d), E the "
        "mechanical work of the 18 joints (sum of |torque x velocity| over time). b before face / open: the mean lift "
        f"(rad) while the body is in the last {BEFORE_FACE} m before a block's face, and on open ground (more than "
        f"{NEAR_BEFORE} m before a block or {NEAR_AFTER} m past it); an adaptive gait lifts before blocks only, a "
        "fixed gait has the same b in both.",
        "## Verdict: does the learned policy beat the best fixed gait?\n\n" + verdict_section(table, inputs),
        "## Where the failed episodes stopped\n\nFor every episode that ended stuck or fallen, the legs with a foot "
        f"at a block's face when it ended (its centre at most {FOOT_BEFORE_FACE} m before the face or "
        f"{FOOT_ON_EDGE} m onto it; `none`: no foot at a face, as on rough ground). `front`: the robot met the "
        "face and did not lift over it; `hind`: the body had passed the face and a hind leg had not.\n\n"
        + stall_table(rows, {"terrain": terrains, "controller": controllers}),
        "## The paper's claims and ours\n\nThe policy \"crosses\" a terrain when at least "
        f"{CROSSES:.0%} of its episodes reach the goal.\n\n" + claims_table(table, terrains),
        f"## Best fixed gait\n\n`best_fixed` = **{inputs.best_gait}** (zero action: the CPG holds it), the best of "
        "the grid below on the training terrains (ranked by success rate, then by the cost of transport of the "
        "episodes that reach the goal, then mean distance up to the goal, then time to goal; seeds disjoint from the "
        "evaluation seeds).\n\n" + grid_table(inputs.grid),
        "## Figures\n\nThe CPG plots show the policy's first episode on each terrain: a, b and omega against forward "
        "distance with the blocks (and bumpy ground) shaded (the paper, section 4.2: a grows for long strides, b "
        "rises before a block). The gait diagrams show the same episodes' foot contacts: stance (dark) and swing "
        "(light) of every leg against time, the figure locomotion people read first.\n\n" + "\n\n".join(figures),
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
    write_text(report_dir / "results.csv", rows.to_csv(index=False))
    write_text(report_dir / "grid.csv", inputs.grid.to_csv(index=False))
    written += [report_dir / "results.csv", report_dir / "grid.csv"]
    plot_success(table, inputs.terrains, inputs.controllers, report_dir / "success.png")
    written.append(report_dir / "success.png")
    for stale in report_dir.glob("cpg_*.png"):  # terrains of an earlier run
        if stale.stem.removeprefix("cpg_") not in inputs.first_policy_episodes:
            stale.unlink()
    for stale in report_dir.glob("gait_*.png"):
        if not _has_feet(inputs.first_policy_episodes.get(stale.stem.removeprefix("gait_"))):
            stale.unlink()
    for terrain, result in inputs.first_policy_episodes.items():
        path = report_dir / f"cpg_{terrain}.png"
        plot_cpg(result, path, inputs.cpg_initial, inputs.goal_distance)
        written.append(path)
        if _has_feet(result):
            plot_gait(result, report_dir / f"gait_{terrain}.png")
            written.append(report_dir / f"gait_{terrain}.png")
    write_text(report_dir / "report.md", markdown(table, inputs, rows))
    learned = [c for c in LEARNED if c in inputs.controllers]
    metrics = {**table, **summary_numbers(table, inputs.terrains, learned)}  # terrains keep the suite's order
    write_text(report_dir / "metrics.json", json.dumps(metrics, indent=2) + "\n")
    return [*written, report_dir / "report.md", report_dir / "metrics.json"]
