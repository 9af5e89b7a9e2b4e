"""The sweep's outputs in reports/sweeps/NAME: metrics.json, results.csv, episodes.csv, trials.csv, targets.csv,
targets_per_terrain.csv, report.md and figures, every file written atomically (metrics.json last).

- success.png: success rate per terrain and condition (bars: mean over seeds, whiskers: bootstrap interval over
  seeds, dots: each seed);
- pareto_<flat>.png: success over the suite against cost of transport on flat ground, one point per
  condition, the Pareto front (more success for less energy) joined.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from hexpipe.atomic import atomic_path, write_json, write_text
from hexpipe.evaluation.metrics import stall_counts
from hexpipe.sweep.tables import ALL, BLIND, Cell, issue10_targets, pareto_front, target_numbers


@dataclass
class SweepReport:
    """Everything the report shows."""

    name: str
    command: str
    conditions: dict[str, tuple[str, ...]]  # name -> overrides
    seeds: Sequence[int]
    terrains: Sequence[str]
    table: dict[str, dict[str, Cell]]  # condition -> terrain -> cell
    improvement: dict[str, dict[str, Cell]]
    per_seed: pd.DataFrame
    episodes: pd.DataFrame
    trials: pd.DataFrame  # one row per trial: trial, condition, seed, status, seconds, host, error
    flat_terrain: str
    confidence: float
    notes: list[str] = field(default_factory=list)
    targets: pd.DataFrame = field(default_factory=pd.DataFrame)  # tables.judge_targets: condition x target
    target_parts: pd.DataFrame = field(default_factory=pd.DataFrame)  # tables.target_parts: ... x terrain
    perception: list[dict[str, Any]] | None = None  # tables.perception_misses of BLIND; None: no BLIND condition


def _save(fig: Any, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)


def plot_success(report: SweepReport, path: Path) -> None:
    """Grouped bars per terrain: mean success over seeds with its bootstrap interval, and each seed as a dot."""
    from matplotlib.figure import Figure

    conditions, terrains = list(report.table), list(report.terrains)
    fig = Figure(figsize=(max(6, 1.7 * len(terrains)), 4), layout="constrained")
    ax = fig.subplots()
    width = 0.8 / max(len(conditions), 1)
    centres = np.arange(len(terrains))
    for k, condition in enumerate(conditions):
        x = centres + (k - (len(conditions) - 1) / 2) * width
        cells = [report.table[condition].get(t, {}) for t in terrains]
        mean = np.array([c.get("success_seed_mean", np.nan) for c in cells])
        low = np.array([c.get("success_seed_mean_low", m) for c, m in zip(cells, mean, strict=True)])
        high = np.array([c.get("success_seed_mean_high", m) for c, m in zip(cells, mean, strict=True)])
        ax.bar(x, np.nan_to_num(mean), width, label=condition, alpha=0.8,
               yerr=[np.nan_to_num(mean - low), np.nan_to_num(high - mean)], capsize=3)
        seeds = report.per_seed[report.per_seed["condition"] == condition]
        for xi, terrain in zip(x, terrains, strict=True):
            rates = seeds.loc[seeds["terrain"] == terrain, "success"].to_numpy(float)
            ax.scatter(np.full(len(rates), xi + width / 4), rates, s=12, color="black", edgecolors="white",
                       linewidths=0.5, zorder=3)
    ax.set_xticks(centres, terrains)
    ax.set_ylim(-0.02, 1.1)
    ax.set_ylabel("success rate")
    ax.set_title(f"mean over training seeds, {report.confidence:.0%} bootstrap interval; dots: seeds", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    _save(fig, path)


def plot_pareto(report: SweepReport, path: Path) -> list[str]:
    """Success over the whole suite (the `all` row; the flat terrain's own when it is the only one) against cost of
    transport on the flat terrain: what a power price buys against what it costs. Returns the conditions on the
    Pareto front."""
    from matplotlib.figure import Figure

    flat = report.flat_terrain
    rows = {c: row for c, row in report.table.items() if flat in row}
    success = {c: row.get(ALL, row[flat]) for c, row in rows.items()}
    points = {c: (success[c].get("success_seed_mean", math.nan), row[flat].get("cost_of_transport", math.nan))
              for c, row in rows.items()}
    front = pareto_front(points)
    fig = Figure(figsize=(6, 4.2), layout="constrained")
    ax = fig.subplots()
    for condition, row in rows.items():
        y, x = points[condition]
        if not (np.isfinite(x) and np.isfinite(y)):
            continue
        cost, hit = row[flat], success[condition]
        xerr = [[x - cost.get("cost_of_transport_low", x)], [cost.get("cost_of_transport_high", x) - x]]
        yerr = [[y - hit.get("success_seed_mean_low", y)], [hit.get("success_seed_mean_high", y) - y]]
        ax.errorbar(x, y, xerr=xerr, yerr=yerr, fmt="o", capsize=3, label=condition)
        ax.annotate(condition, (x, y), textcoords="offset points", xytext=(5, 5), fontsize=8)
    if len(front) > 1:
        ordered = sorted(front, key=lambda c: points[c][1])
        ax.plot([points[c][1] for c in ordered], [points[c][0] for c in ordered], "k--", lw=1, label="Pareto front")
    ax.margins(0.15)
    ax.set_xlabel(f"cost of transport on {flat} (episodes that reach the goal)")
    ax.set_ylabel("success rate over the suite (mean over seeds)")
    ax.set_title(f"more success for less energy is up and to the left ({report.confidence:.0%} intervals)",
                 fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    _save(fig, path)
    return front


def _fmt(cell: Cell, key: str, spec: str) -> str:
    """'value [low, high]', or the value alone where no interval exists; '(k seeds)' when fewer seeds than the cell
    has contributed (time and energy count only the seeds with an episode that reached the goal)."""
    if key not in cell:
        return "-"
    value = format(cell[key], spec)
    if f"{key}_low" in cell:
        value = f"{value} [{format(cell[f'{key}_low'], spec)}, {format(cell[f'{key}_high'], spec)}]"
    if f"{key}_seeds" in cell and cell[f"{key}_seeds"] < cell.get("seeds", 0):
        n = cell[f"{key}_seeds"]
        value += f" ({n} seed{'s' if n != 1 else ''})"
    return value


def _r2(value: float) -> str:
    return f"{value:.3f}" if isinstance(value, float) and np.isfinite(value) else "-"


def _table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


def results_rows(table: dict[str, dict[str, Cell]]) -> pd.DataFrame:
    """One row per (condition, terrain or all) with every statistic as a column (results.csv)."""
    rows = [{"condition": c, "terrain": t, **cell} for c, row in table.items() for t, cell in row.items()]
    return pd.DataFrame(rows)


def _estimate(value: float, low: float, high: float, spec: str) -> str:
    """'value [low, high]', the value alone without an interval, '-' without a value."""
    if not np.isfinite(value):
        return "-"
    out = format(value, spec)
    return f"{out} [{format(low, spec)}, {format(high, spec)}]" if np.isfinite([low, high]).all() else out


def _target_spec(target: str) -> str:
    return ".1f" if "time" in target else ".2f"


def targets_section(report: SweepReport) -> str:
    """'## Issue 10 targets': target x condition, each 'value [low, high] ✓/✗', the met counts, perception."""
    judged, level = report.targets, f"{report.confidence:.0%}"
    conditions = list(dict.fromkeys(judged["condition"])) if len(judged) else []
    if not conditions:
        return "## Issue 10 targets\n\n_No complete trial has policy episodes to judge._"
    complete = report.trials[report.trials["status"] == "ok"].groupby("condition").size()
    rows = []
    for goal in issue10_targets(report.flat_terrain):
        target, mine = goal.key, judged[judged["target"] == goal.key]
        cells = []
        for condition in conditions:
            row = mine[mine["condition"] == condition]
            if row.empty:
                cells.append("-")
                continue
            r = row.iloc[0]
            cell = f"{_estimate(r.value, r.low, r.high, _target_spec(target))} {'✓' if r.met else '✗'}"
            if len(goal.terrains) != 1:  # over several terrains: name the worst
                cell += f" ({r.terrain})"
            if 0 < r.seeds < complete.get(condition, 0):
                cell += f" ({r.seeds} seed{'s' if r.seeds != 1 else ''})"
            cells.append(cell)
        rows.append((goal.label, f"{'≥' if goal.above else '≤'} {goal.threshold:g}", *cells))
    met = judged.groupby("condition", sort=False)["met"].agg(["sum", "size"])
    rows.append(("**met**", "", *(f"{int(met.loc[c, 'sum'])} of {int(met.loc[c, 'size'])}" for c in conditions)))
    reference = conditions[0]
    if report.perception is None:
        perception = (f"**Perception matters:** not judged: no condition named `{BLIND}` besides the first "
                      f"(`{reference}`).")
    elif not report.perception:
        perception = (f"**Perception matters** (`{BLIND}` against `{reference}`): no. `{BLIND}` misses no target "
                      f"by a margin outside the intervals.")
    else:
        missed = [f"{m['target']} on {m['terrain']}: "
                  f"{_estimate(m['value'], m['low'], m['high'], _target_spec(m['target']))} against "
                  f"{_estimate(m['reference'], m['reference_low'], m['reference_high'], _target_spec(m['target']))}"
                  for m in report.perception]
        perception = (f"**Perception matters** (`{BLIND}` against `{reference}`): yes. `{BLIND}` misses, with "
                      f"intervals apart: " + "; ".join(missed) + ".")
    return (
        "## Issue 10 targets\n\n"
        "The learned policy (controller `policy`) of each condition against issue 10's targets. Each value is the "
        "mean over training seeds of a per-seed figure, with its "
        f"{level} percentile bootstrap interval over seeds; ✓/✗ is decided on that mean, and the interval shows "
        "whether it is clear of the threshold. Success is each seed's success rate; time to goal and cost of "
        "transport are over the episodes that reached the goal. A comparison with the best fixed gait is per seed, "
        "against the `best_fixed` controller of the same trial on the same episodes. A target over several terrains "
        "shows its worst terrain, named in brackets (every terrain: targets_per_terrain.csv). \"-\": not "
        "measured.\n\n"
        + _table(("target", "threshold", *(f"`{c}`" for c in conditions)), rows) + "\n\n" + perception)


def markdown(report: SweepReport, front: list[str] | None) -> str:
    level = f"{report.confidence:.0%}"
    grid = [(f"`{c}`", ", ".join(f"`{o}`" for o in o_) or "(params as given)",
             str(int((report.trials["condition"] == c).sum())),
             str(int(((report.trials["condition"] == c) & (report.trials["status"] == "ok")).sum())))
            for c, o_ in report.conditions.items()]
    results = []
    for terrain in [*report.terrains, ALL]:
        for condition, row in report.table.items():
            cell = row.get(terrain)
            if cell is None:
                continue
            results.append((terrain, condition, _fmt(cell, "success_rate", ".2f"),
                            _fmt(cell, "success_seed_mean", ".2f"), _fmt(cell, "success_iqm", ".2f"),
                            _fmt(cell, "time_to_goal", ".1f"), _fmt(cell, "cost_of_transport", ".2f"),
                            str(cell["seeds"]), str(cell["episodes"])))
    improvement = [(pair.replace("_vs_", " > "), terrain, _fmt(cell, "probability", ".2f"))
                   for pair, row in report.improvement.items() for terrain, cell in row.items()]
    own_encoders = "encoder" in report.trials
    trials = [(r.trial, *((f"`{r.encoder}`", _r2(r.distance_r2), _r2(r.height_r2)) if own_encoders else ()),
               r.status, f"{r.seconds:.0f}" if isinstance(r.seconds, float) and np.isfinite(r.seconds)
               else "-", str(r.host) if isinstance(r.host, str) else "-",
               str(r.error).replace("|", "/") if isinstance(r.error, str) else "")
              for r in report.trials.itertuples()]
    trial_header = ("trial", *(("encoder", "distance R²", "height R²") if own_encoders else ()), "status",
                    "seconds", "host", "error")
    parts = [
        f"# Sweep `{report.name}`",
        f"Produced by:\n\n```\n{report.command}\n```",
        "Each trial trains PPO with its own seed (`ppo.seed`) and evaluates the policy on the same seeded episodes "
        "(`eval.seed`); with `ppo.candidates` K above 1 it trains seeds seed, seed + 1000, ... and evaluates the one "
        "with the best validation return, as `train-ppo` does (each trial's `selection.json`). "
        + ("Each trial also trains its own encoder with `vae.seed` = its seed (`sweep.train_encoder`): the spread "
           "over seeds includes the encoder's draw; the Trials table names each encoder and its rise probes. "
           if own_encoders else "")
        + f"Seeds: {', '.join(map(str, report.seeds))}.\n\n"
        + _table(("condition", "overrides", "trials", "complete"), grid),
        "## Success, time to goal and cost of transport\n\n"
        f"Intervals are {level}. **success (episodes)**: every episode of every seed pooled, Wilson score interval "
        "(how sure we are of this exact set of policies). **success (seeds)**: mean over training seeds of each "
        "seed's success rate, percentile bootstrap over seeds, resampling whole seeds on the `all` rows (how sure we "
        "are of the training recipe: this is the one to compare conditions with). **IQM**: interquartile mean of "
        "the per-seed success rates (the plain mean below 4 seeds), bootstrap interval. Time to goal (s) and cost of "
        "transport: means over seeds of each seed's mean over the episodes that reached the goal, bootstrap over "
        "those seeds.\n\n"
        + _table(("terrain", "condition", "success (episodes)", "success (seeds)", "IQM", "time to goal (s)",
                  "cost of transport", "seeds", "episodes"), results),
    ]
    parts.append(targets_section(report))
    policy = report.episodes[report.episodes["controller"] == "policy"] if len(report.episodes) else report.episodes
    if "stall_legs" in policy:
        parts.append(
            "## Where the policies' failed episodes stopped\n\nEvery seed's stuck or fallen episodes, by the legs with "
            "a foot at a block's face when it ended (`front`: it met the face and did not lift over it; `hind`: the "
            "body had passed the face and a hind leg had not; `none`: no foot at a face; `-`: recorded before "
            "hexpipe kept this).\n\n"
            + _table(("terrain", "condition", "stuck or fallen", "legs with a foot at a block face"),
                     [(f"`{t}`", f"`{c}`", str(n), legs) for (t, c), n, legs in
                      stall_counts(policy, {"terrain": report.terrains, "condition": list(report.conditions)})]))
    if improvement:
        parts.append(
            "## Probability of improvement\n\nP(a > b): the chance that a seed of condition a has a higher success "
            "rate than a seed of condition b (ties count half; Mann-Whitney U over seed pairs, averaged over terrains "
            f"on the `all` row), with a {level} bootstrap interval over whole seeds. 0.5 = no difference.\n\n"
            + _table(("a > b", "terrain", "probability"), improvement))
    figures = ["![success per terrain](success.png)"]
    if front is not None:
        figures.append(f"![success over the suite against cost of transport on {report.flat_terrain}](pareto_"
                       f"{report.flat_terrain}.png)\n\nOn the Pareto front (success over the suite, cost of "
                       f"transport on {report.flat_terrain}): {', '.join(front) or 'none'}.")
    parts.append("## Figures\n\n" + "\n\n".join(figures))
    parts.append("## Trials\n\n" + _table(trial_header, trials)
                 + "\n\nPer-trial reports: `TRIAL/ppo/` and `TRIAL/eval/` beside this file"
                 + (", each encoder's in `encoders/ENCODER/`." if own_encoders else "."))
    if report.notes:
        parts.append("## Notes\n\n" + "\n".join(f"- {n}" for n in report.notes))
    return "\n\n".join(parts) + "\n"


def write_report(out_dir: Path, report: SweepReport) -> list[Path]:
    """Write every file of the sweep's report; metrics.json last, so its presence means the rest is there."""
    out_dir.mkdir(parents=True, exist_ok=True)
    written = [out_dir / n for n in ("results.csv", "episodes.csv", "per_seed.csv", "trials.csv", "targets.csv",
                                     "targets_per_terrain.csv")]
    frames = (results_rows(report.table), report.episodes, report.per_seed, report.trials, report.targets,
              report.target_parts)
    for path, frame in zip(written, frames, strict=True):
        write_text(path, frame.to_csv(index=False))
    front = None
    if report.table:
        plot_success(report, out_dir / "success.png")
        written.append(out_dir / "success.png")
    if any(report.flat_terrain in row for row in report.table.values()):
        front = plot_pareto(report, out_dir / f"pareto_{report.flat_terrain}.png")
        written.append(out_dir / f"pareto_{report.flat_terrain}.png")
    else:
        report.notes.append(f"No Pareto plot: the flat terrain `{report.flat_terrain}` (sweep.flat_terrain) is not "
                            "in the evaluated terrains; add it to eval.terrains.")
    write_text(out_dir / "report.md", markdown(report, front))
    trials = report.trials
    write_json(out_dir / "metrics.json", {
        "conditions": report.table, "improvement": report.improvement,
        "trials": {"complete": int((trials["status"] == "ok").sum()), "failed": int((trials["status"] == "failed")
                                                                                    .sum()), "total": len(trials)},
        **(target_numbers(report.targets, report.target_parts, report.perception) if len(report.targets) else {}),
    })
    return [*written, out_dir / "report.md", out_dir / "metrics.json"]
