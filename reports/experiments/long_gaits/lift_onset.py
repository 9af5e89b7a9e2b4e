"""When the lift rises before a block, per condition: from the sweep trials' per-step traces.

    .venv/bin/python reports/experiments/long_gaits/lift_onset.py data/sweeps/stride50:cycle125 \
        data/sweeps/stride60:stride60 [--threshold 0.45]

For each policy episode on the one-face terrains (the face at 0.6, 1.0 or 1.6 m), the first step where the swing
lift (`lift`: b, or the reflex's where higher) reaches the threshold, as the lead before the front feet meet the
face: in metres of base travel (the front feet stand about FRONT_REACH m ahead of the base) and in seconds. Prints
the median lead per condition, terrain and outcome (crossed: the base reached 2.9 m), how many episodes never lift
that high in the metre before the face, and the failed episodes per trial.
The traces are `DATA/TRIAL/eval/cpg_traces.csv.gz`, written by each sweep trial and not committed: rerun the
sweep to remake them.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

from hexpipe.sim.terrain.recipes import SCENARIOS

ONE_FACE = ("single_block", "tall_block", "low_block", "block_near", "block_far")  # one 0.3 m deep block each
FACES = {name: SCENARIOS[name].boxes[0].face for name in ONE_FACE}  # m: the block's near face along x
FRONT_REACH = 0.47  # m: the front feet ahead of the base at the start (terrain recipes' face check)


def read_traces(source: str, terrains, columns: list[str]) -> pd.DataFrame:
    """The policy's per-step traces on `terrains` from every trial of DATA_DIR:CONDITION (`columns` of
    cpg_traces.csv.gz, with `terrain` and `controller` among them), tagged with condition and trial; a clear one-line
    error for a malformed source, no trial, or an unreadable file."""
    folder, sep, condition = source.partition(":")
    paths = sorted(Path(folder).glob(f"{condition}-seed*/eval/cpg_traces.csv.gz"))
    if not sep or not paths:
        raise SystemExit(f"error: {source!r}: want DATA_DIR:CONDITION, with "
                         "DATA_DIR/CONDITION-seed*/eval/cpg_traces.csv.gz")
    frames = []
    for path in paths:
        try:
            d = pd.read_csv(path, usecols=columns)
        except (OSError, ValueError, EOFError) as exc:  # unreadable, truncated, or a column missing
            raise SystemExit(f"error: {path}: not a sweep trial's cpg traces ({exc})") from None
        d = d[(d["controller"] == "policy") & d["terrain"].isin(terrains)]
        frames.append(d.assign(condition=condition, trial=path.parents[1].name))
    return pd.concat(frames)


def _lead(steps: pd.DataFrame, threshold: float) -> dict:
    face = FACES[steps["terrain"].iloc[0]]
    meet = face - FRONT_REACH  # base travel where the front feet reach the face
    reached = steps[steps["distance"] >= meet]
    t_meet = reached["time"].iloc[0] if len(reached) else float("nan")
    before = steps[(steps["distance"] < meet) & (steps["distance"] > meet - 1.0)]
    up = before[before["lift"] >= threshold]
    if up.empty:
        return {"lead_m": float("nan"), "lead_s": float("nan")}
    first = up.iloc[0]
    return {"lead_m": meet - first["distance"], "lead_s": t_meet - first["time"]}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("sources", nargs="+", metavar="DATA_DIR:CONDITION")
    ap.add_argument("--threshold", type=float, default=0.45)
    a = ap.parse_args()
    traces = pd.concat([read_traces(s, FACES, ["terrain", "controller", "episode", "time", "distance", "lift"])
                        for s in a.sources])
    final = traces.groupby(["condition", "trial", "terrain", "episode"])["distance"].max().rename("final")
    rows = []
    for key, steps in traces.groupby(["condition", "trial", "terrain", "episode"]):
        rows.append({**dict(zip(["condition", "trial", "terrain", "episode"], key, strict=True)),
                     **_lead(steps.sort_values("time"), a.threshold)})
    table = pd.DataFrame(rows).join(final, on=["condition", "trial", "terrain", "episode"])
    table["crossed"] = table["final"] >= 2.9
    table["lifted"] = table["lead_m"].notna()
    with pd.option_context("display.width", 200):
        print(f"lift >= {a.threshold} rad first reached, lead before the front feet meet the face (median), "
              "episodes, and episodes never that high in the metre before")
        summary = table.groupby(["condition", "terrain", "crossed"]).agg(
            episodes=("lifted", "size"), never=("lifted", lambda s: int((~s).sum())),
            lead_m=("lead_m", "median"), lead_s=("lead_s", "median"))
        print(summary.round(2).to_string())
        print("\nall one-face terrains together")
        print(table.groupby(["condition", "crossed"]).agg(
            episodes=("lifted", "size"), never=("lifted", lambda s: int((~s).sum())),
            lead_m=("lead_m", "median"), lead_s=("lead_s", "median")).round(2).to_string())
        print("\nfailed episodes per trial, and how many never lifted that high in the metre before the face")
        failed = table[~table["crossed"]]
        print(failed.groupby(["condition", "trial"]).agg(
            failed=("lifted", "size"), never=("lifted", lambda s: int((~s).sum()))).to_string())


if __name__ == "__main__":
    main()
