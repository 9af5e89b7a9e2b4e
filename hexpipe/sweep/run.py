"""`hexpipe sweep` end to end: expand the grid, run what is missing on Ray, then the statistics and the report."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pandas as pd

from hexpipe.config import ConfigError, Params
from hexpipe.sweep import tables
from hexpipe.sweep.grid import Trial, expand
from hexpipe.sweep.report import SweepReport, write_report
from hexpipe.sweep.runner import Outcome, run_trials
from hexpipe.sweep.store import load_failure

FEW_SEEDS = 6  # below this many seeds the report warns that its intervals are too narrow to decide on


def trials_frame(params: Params, trials: list[Trial], outcome: Outcome) -> pd.DataFrame:
    rows = []
    for trial in trials:
        record = outcome.results.get(trial.name)
        failure = outcome.failures.get(trial.name) or (None if record else load_failure(params, trial))
        status = "ok" if record else "failed" if failure else "not run"
        rows.append({"trial": trial.name, "condition": trial.condition, "seed": trial.seed, "status": status,
                     "seconds": record["seconds"]["total"] if record else float("nan"),
                     "host": record.get("host") if record else None, "node": record.get("node") if record else None,
                     "code": record.get("code") if record else None,
                     "error": failure["error"] if failure and not record else None})
        if trial.encoder is not None:  # the encoder it trained and the latent's rise probes (R², held-out frames)
            vae = (record or {}).get("vae", {})
            rows[-1] |= {"encoder": trial.encoder, "distance_r2": vae.get("probe/rise_distance_r2", float("nan")),
                         "height_r2": vae.get("probe/rise_height_r2", float("nan"))}
    return pd.DataFrame(rows)


def build_report(params: Params, trials: list[Trial], outcome: Outcome, command: str) -> SweepReport:
    cfg = params.sweep
    records = [outcome.results[t.name] for t in trials if t.name in outcome.results]
    episodes = tables.episodes_frame(records)
    policy = episodes[episodes["controller"] == "policy"] if len(episodes) else episodes
    seeds = tables.per_seed(policy)
    terrains = list(dict.fromkeys(policy["terrain"])) if len(policy) else []
    conditions = list(cfg.conditions)
    args = (cfg.confidence, cfg.resamples)
    table = tables.summarise(seeds, conditions, terrains, *args)
    pairs = tables.default_pairs([c for c in conditions if c in table], cfg.compare) if table else []
    trials_df = trials_frame(params, trials, outcome)
    ran = [c for c in conditions if c in table]
    parts = tables.target_parts(episodes, ran, cfg.flat_terrain, *args)
    blind = tables.BLIND in ran[1:]
    notes = []
    unread = [c for c in ran if tables.HOME_TERRAIN in set(seeds.loc[seeds["condition"] == c, "terrain"])
              and not ((parts["condition"] == c) & (parts["target"] == "adaptation")).any()]
    if unread:
        notes.append(f"Adaptation shows \"-\" for {', '.join(unread)}: their trial records have no b_before_block / "
                     "b_open (recorded from before the sweep kept them); refresh the records from each trial's "
                     "eval/results.csv.")
    missing = trials_df[trials_df["status"] != "ok"]
    if len(missing):
        notes.append(f"{len(missing)} of {len(trials_df)} trials have no result ({', '.join(missing['trial'])}): "
                     "the statistics use the complete ones; rerun the same command to retry them.")
    if len(set(trials_df["code"].dropna())) > 1:
        notes.append("The trials ran under different hexpipe code (column `code` in trials.csv).")
    if len(cfg.seeds) < 2:
        notes.append("One seed: no interval over seeds can be computed (use sweep.seeds with at least 6).")
    elif len(cfg.seeds) < FEW_SEEDS:
        notes.append(f"{len(cfg.seeds)} seeds: a bootstrap over so few seeds understates their spread (two 3-seed "
                     "halves of one comparison gave P intervals that exclude each other; reports/experiments/README.md,"
                     f" \"rollout_forward\"). Read P as a direction, not a decision; use {FEW_SEEDS} or more seeds.")
    return SweepReport(
        name=cfg.name, command=command, conditions=dict(cfg.conditions), seeds=cfg.seeds, terrains=terrains,
        table=table, improvement=tables.improvements(seeds, pairs, terrains, *args), per_seed=seeds,
        episodes=episodes, trials=trials_df, flat_terrain=cfg.flat_terrain, confidence=cfg.confidence, notes=notes,
        targets=tables.judge_targets(parts, ran, cfg.flat_terrain), target_parts=parts,
        perception=tables.perception_misses(parts, cfg.flat_terrain, tables.BLIND, ran[0]) if blind else None,
    )


def run_sweep(
    params: Params, command: str, address: str | None = None, cpus: int | None = None, show_progress: bool = True,
    log: Callable[[str], None] = print,
) -> tuple[Outcome, Path]:
    """Run every trial of params.sweep that has no complete result, then write reports/sweeps/NAME."""
    trials = expand(params)  # ConfigError before anything runs
    if params.sweep.train_encoder and not Path(params.vae.data_dir).is_dir():  # else every trial fails alike
        raise ConfigError(f"vae.data_dir {params.vae.data_dir}: no such folder, and --train-encoder trains each "
                          "trial's encoder from it (run the collect stage first: dvc repro collect)")
    outcome = run_trials(params, trials, address=address, cpus=params.sweep.cpus if cpus is None else cpus,
                         root=Path.cwd(), show_progress=show_progress, log=log)
    out_dir = Path(params.sweep.report_dir) / params.sweep.name
    write_report(out_dir, build_report(params, trials, outcome, command))
    return outcome, out_dir
