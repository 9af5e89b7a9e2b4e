"""Whole pipelines with best of 3: for each pipeline seed p whose three candidates (p, p+1000, p+2000) were trained
and evaluated as sweep trials, the one train-ppo keeps (the highest mean validation return), against the single
run a pipeline without selection trains (candidate p), judged on issue 10's targets over pipelines.
With --candidates K, best of K instead (seeds p, p+1000, ..., p+(K-1)*1000; only pipelines with all K trained).

    .venv/bin/python reports/experiments/select/pipelines.py reports/sweeps/epyc30 reports/sweeps/cand ... \
        [--validation reports/experiments/select/select30_validation.csv ...] [--csv-first] [--repro reports]

A trial's validation return is the `selection.json` its sweep record carries (trials run since ppo.candidates,
which train-ppo scores itself), or else the mean `env_return` of its episodes in a validate.py CSV (the same
60 episodes and the same sum: validate.py and hexpipe/rl/selection.py agree to the last digit on seed 0's first
four). Trials are matched by their data folder, data/sweeps/NAME/TRIAL.

--repro REPORTS adds `make repro`'s own pipeline: the candidates' returns from REPORTS/ppo/selection.json, and the
kept policy's first --episodes (10) evaluation episodes per terrain from REPORTS/eval/results.csv, which are the
sweep trials' episodes (the same seeds from eval.seed, deterministic), for the policy, the open-loop gait and the
best fixed gait (the same a=0.4, b=0.4, omega=pi when the repro's 27-gait grid picks it: the script says which it
picked). Without selection the pipeline is its first candidate alone, known only where that is the one kept.

--lift-floor X keeps, of a pipeline's candidates, the highest validation return among those whose validation lift
(mean b before a block face minus mean b on open ground, over their episodes in the --validation CSVs, which
validate.py writes) is at least X rad; where none is, the highest return as before.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd

from hexpipe.rl.selection import SEED_STRIDE, candidate_seeds, choose
from hexpipe.sweep import tables

CANDIDATES = 3
REPRO_CONTROLLERS = ("policy", "best_fixed", "open_loop")  # the controllers a sweep trial evaluates
SINGLE = "single"


def load_records(sweeps: list[Path], condition: str | None = None) -> list[dict]:
    """Every complete trial record of the sweeps (of `condition` only, if named)."""
    records = []
    for sweep in sweeps:
        for path in sorted(sweep.glob("*/result.json")):
            record = json.loads(path.read_text())
            if record.get("status") == "ok" and condition in (None, record.get("condition")):
                records.append({**record, "data": f"data/sweeps/{sweep.name}/{path.parent.name}"})
    return records


def validation_return(record: dict, csv: pd.Series, csv_first: bool = False) -> float:
    if csv_first and record["data"] in csv.index:
        return float(csv[record["data"]])
    selection = record.get("selection") or {}
    own = selection.get("candidates", {}).get(str(record["seed"]))
    if own is not None:
        return float(own["return"])
    if record["data"] in csv.index:
        return float(csv[record["data"]])
    return float("nan")


def repro_pipeline(reports: Path, episodes: int) -> tuple[int, list[float], dict]:
    """`make repro`'s pipeline seed, its candidates' validation returns, and its kept policy as a trial record."""
    for path in (reports / "ppo" / "selection.json", reports / "eval" / "results.csv"):
        if not path.is_file():
            raise SystemExit(f"error: --repro {reports}: {path} not found (a make repro reports folder holds it)")
    selection = json.loads((reports / "ppo" / "selection.json").read_text())
    # one candidate and no validation episodes (`ppo.candidates: 1`, `validation_episodes: 0`, as adopt_order1 ran)
    seeds = sorted(int(s) for s in selection["candidates"]) or [int(selection["chosen_seed"])]
    returns = [float(selection["candidates"].get(str(s), {}).get("return", "nan")) for s in seeds]
    rows = pd.read_csv(reports / "eval" / "results.csv")
    rows = rows[rows["controller"].isin(REPRO_CONTROLLERS) & (rows["episode"] < episodes)]
    gait = rows.loc[rows["controller"] == "best_fixed", "gait"].dropna().unique().tolist()
    print(f"make repro ({reports}): seeds {seeds}, kept {selection['chosen_seed']}; its best fixed gait {gait}; "
          f"first {episodes} episodes a terrain")
    record = {"seed": int(selection["chosen_seed"]), "trial": "make-repro", "data": str(reports),
              "episodes": rows.drop(columns=["gait"]).to_dict("records")}
    return seeds[0], returns, record


def main(sweeps: list[Path], validations: list[Path], flat: str = "flat", repro: Path | None = None,
         repro_episodes: int = 10, csv_first: bool = False, condition: str | None = None,
         candidates: int = CANDIDATES, lift_floor: float | None = None) -> None:
    if candidates < 1:
        raise SystemExit(f"error: --candidates {candidates}: want 1 or more")
    best = f"best{candidates}"
    frame = pd.concat([pd.read_csv(v) for v in validations]) if validations else pd.DataFrame(columns=["trial"])
    if validations and not {"trial", "env_return"} <= set(frame.columns):
        raise SystemExit(f"error: --validation {', '.join(map(str, validations))}: want validate.py's CSVs "
                         "(columns trial and env_return)")
    csv = frame.groupby("trial")["env_return"].mean() if validations else pd.Series(dtype=float)
    lifts = validation_lifts(frame) if lift_floor is not None else pd.Series(dtype=float)
    records = load_records(sweeps, condition)
    if not records:
        raise SystemExit(f"error: no complete trials{f' of condition {condition!r}' if condition else ''} in "
                         f"{', '.join(map(str, sweeps))}")
    by_seed = {}
    for record in records:
        record["v_return"] = validation_return(record, csv, csv_first)
        by_seed.setdefault(record["seed"], record)  # the first sweep named wins a seed run twice
    pipelines = sorted({s % SEED_STRIDE for s in by_seed
                        if all(c in by_seed for c in candidate_seeds(s % SEED_STRIDE, candidates))})
    rows, chosen_records, single_records = [], [], []
    for p in pipelines:
        cands = [by_seed[c] for c in candidate_seeds(p, candidates)]
        returns = [c["v_return"] for c in cands]
        if any(np.isnan(returns)):
            print(f"pipeline {p}: a candidate has no validation return ({[c['data'] for c in cands]}); left out")
            continue
        lift = [lifts.get(c["data"], np.nan) for c in cands]
        kept = cands[choose(returns) if lift_floor is None else choose_with_lift(returns, lift, lift_floor)]
        chosen_records.append({**kept, "condition": best, "seed": p})
        single_records.append({**cands[0], "condition": SINGLE, "seed": p})
        rows.append({"pipeline": p, **{f"return_p+{i * SEED_STRIDE}": round(r, 1) for i, r in enumerate(returns)},
                     **({f"v_lift_p+{i * SEED_STRIDE}": round(x, 3) for i, x in enumerate(lift)}
                        if lift_floor is not None else {}),
                     "kept": kept["seed"]})
    if repro is not None:
        p, returns, kept = repro_pipeline(repro, repro_episodes)
        if p in pipelines:
            raise SystemExit(f"error: pipeline {p} is both in the sweeps and --repro {repro}")
        if len(returns) != candidates:
            raise SystemExit(f"error: --repro {repro} trained {len(returns)} candidates, not --candidates {candidates}")
        chosen_records.append({**kept, "condition": best, "seed": p})
        if kept["seed"] == p:
            single_records.append({**kept, "condition": SINGLE, "seed": p})
        else:
            print(f"pipeline {p} (make repro): kept {kept['seed']}, and seed {p} alone was not evaluated; "
                  "its single run is left out")
        rows.append({"pipeline": p, **{f"return_p+{i * SEED_STRIDE}": round(r, 1) for i, r in enumerate(returns)},
                     "kept": kept["seed"]})
    if not rows:
        raise SystemExit(f"error: no pipeline has all {candidates} candidates (seeds p, p+{SEED_STRIDE}, ...) "
                         f"among the complete trials of {', '.join(map(str, sweeps))}")
    print(pd.DataFrame(rows).to_string(index=False))
    episodes = tables.episodes_frame(chosen_records + single_records)
    outcome = outcomes(episodes)
    print("\nper pipeline (policy, sweep-scale evaluation): suite = success on every terrain but flat ground")
    print(outcome.round(3).to_string())
    print_targets(episodes, [best, SINGLE], flat, "pipelines", width=7)
    paired = outcome.pivot(index="pipeline", columns="condition")
    for column in ("lift", "suite", "extra"):
        diff = (paired[column][best] - paired[column][SINGLE]).to_numpy(float)
        known = diff[~np.isnan(diff)]  # a --repro pipeline that kept another seed has no single run
        print(f"{best} - single, {column}: mean {known.mean():+.3f} over {len(known)} pipelines with both "
              f"(changed in {(np.abs(known) > 1e-9).sum()}; per pipeline {np.round(diff, 3).tolist()})")


def validation_lifts(frame: pd.DataFrame) -> pd.Series:
    """Per trial (data folder), mean b before a face minus mean b on open ground over its validation episodes
    (rad). One line, not a traceback, when the CSVs lack those columns; a trial they lack has no lift (NaN)."""
    missing = {"b_before_block", "b_open"} - set(frame.columns)
    if missing:
        raise SystemExit(f"error: --lift-floor needs --validation CSVs with {sorted(missing)} (validate.py has them)")
    by_trial = frame.groupby("trial")
    return by_trial["b_before_block"].mean() - by_trial["b_open"].mean()


def choose_with_lift(returns: list[float], lifts: list[float], floor: float) -> int:
    """The highest return among the candidates whose validation lift is at least `floor` (rad); with none, the
    highest return (`choose`, the rule train-ppo uses)."""
    eligible = np.asarray(lifts, dtype=float) >= floor  # a NaN lift (no face seen) is not eligible
    if not eligible.any():
        return choose(returns)
    return int(np.argmax(np.where(eligible, np.asarray(returns, dtype=float), -np.inf)))


def print_targets(episodes: pd.DataFrame, conditions: list[str], flat: str, unit: str, width: int) -> None:
    """Issue 10's targets for each condition over its trials (`unit`: what a trial is called), and the count met."""
    judged = tables.judge_targets(tables.target_parts(episodes, conditions, flat), conditions, flat)
    print(f"\nissue 10's targets over {unit} (mean over {unit}, 95% bootstrap over {unit}; worst terrain):")
    for row in judged.itertuples():
        print(f"{row.condition:>{width}} {row.target:<24} {row.terrain:<13} {row.value:+.3f} [{row.low:+.3f}, "
              f"{row.high:+.3f}] {'met' if row.met else 'missed'} ({row.seeds} {unit})")
    for condition in conditions:
        mine = judged[judged["condition"] == condition]
        print(f"{condition}: {int(mine['met'].sum())} of {len(mine)} targets met")


def outcomes(episodes: pd.DataFrame) -> pd.DataFrame:
    policy = episodes[episodes["controller"] == tables.LEARNED]
    lift = tables.adaptation_per_seed(episodes).set_index(["condition", "train_seed"])["adaptation"]
    rows = []
    for (condition, seed), g in policy.groupby(["condition", "train_seed"]):
        flat = g[(g["terrain"] == "flat") & g["success"]]
        rows.append({"condition": condition, "pipeline": seed, "trial": g["trial"].iloc[0],
                     "suite": g.loc[g["terrain"] != "flat", "success"].mean(),
                     "extra": g.loc[g["terrain"] == "extra_blocks", "success"].mean(),
                     "lift": lift.get((condition, seed), np.nan), "flat_cot": flat["cost_of_transport"].mean()})
    return pd.DataFrame(rows)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sweeps", nargs="+", type=Path)
    ap.add_argument("--validation", action="append", default=[], type=Path)
    ap.add_argument("--repro", type=Path, help="a reports folder of `make repro` to add as a pipeline")
    ap.add_argument("--episodes", type=int, default=10, help="--repro's episodes a terrain (the sweeps' eval.episodes)")
    ap.add_argument("--csv-first", action="store_true",
                    help="score trials by the --validation CSVs even where their records carry their own returns "
                         "(another validation set than train-ppo's)")
    ap.add_argument("--condition", help="read only this condition's trials (a sweep of several conditions)")
    ap.add_argument("--candidates", type=int, default=CANDIDATES, help="best of this many (ppo.candidates)")
    ap.add_argument("--lift-floor", type=float, help="keep the best return among candidates lifting at least this "
                                                      "much (rad) in the --validation CSVs")
    a = ap.parse_args()
    if a.lift_floor is not None and not a.validation:
        ap.error("--lift-floor needs --validation CSVs (validate.py's, with b_before_block and b_open)")
    main(a.sweeps, a.validation, repro=a.repro, repro_episodes=a.episodes, csv_first=a.csv_first,
         condition=a.condition, candidates=a.candidates, lift_floor=a.lift_floor)
