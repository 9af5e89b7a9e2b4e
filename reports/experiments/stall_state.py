"""The CPG parameters a policy held in the last seconds of each episode, by how the episode ended: did the failed
ones drop the lift b (feet dragging) or sit at the slowest stride (omega at its floor)?

Reads sweep trials' data folders (`data/sweeps/NAME/TRIAL`, which hold eval/cpg_traces.csv.gz) and each trial's
record beside it (`reports/sweeps/NAME/TRIAL/result.json`, found from the same repository root):

    .venv/bin/python reports/experiments/stall_state.py /work/wt-levers/data/sweeps/levers/default-seed{0,1,2} ...

Episodes on flat ground are left out (nothing there to fail at). Ends: `success`, `face` (stuck or fallen with a
foot at a block face), `noface` (stuck or fallen with none), `time_limit`.
"""

import argparse
import json
from pathlib import Path

import pandas as pd


def trial_files(trial_data: Path) -> tuple[Path, Path]:
    """(its cpg_traces.csv.gz, reports/sweeps/NAME/TRIAL/result.json in the same repository) for a
    data/sweeps/NAME/TRIAL folder; SystemExit with one line when either is missing."""
    traces = trial_data / "eval" / "cpg_traces.csv.gz"
    parts = trial_data.resolve().parts
    record = Path(*parts[:-4], "reports", "sweeps", *parts[-2:], "result.json") if len(parts) > 4 else None
    for path in (traces, record):
        if path is None or not path.is_file():
            raise SystemExit(f"error: {trial_data} is not a complete sweep trial folder (data/sweeps/NAME/TRIAL): "
                             f"missing {path or 'reports/sweeps/NAME/TRIAL/result.json'}")
    return traces, record


def end_kind(episode: dict) -> str:
    if episode["success"]:
        return "success"
    if episode["termination"] == "time_limit":
        return "time_limit"
    return "noface" if episode.get("stall_legs") == "none" else "face"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trials", nargs="+", type=Path, help="data/sweeps/NAME/TRIAL folders")
    parser.add_argument("--seconds", type=float, default=4.0, help="the end window (s); 4 = the stuck check's")
    parser.add_argument("--omega-floor", type=float, default=1.6, help="omega below this counts as at the floor")
    args = parser.parse_args()
    rows = []
    for trial in args.trials:
        traces_path, record_path = trial_files(trial)
        record = json.loads(record_path.read_text())
        traces = pd.read_csv(traces_path)
        traces = traces[traces["controller"] == "policy"]
        for episode in record["episodes"]:
            if episode["controller"] != "policy" or episode["terrain"] == "flat":
                continue
            trace = traces[(traces["terrain"] == episode["terrain"]) & (traces["episode"] == episode["episode"])]
            if trace.empty:
                continue
            last = trace[trace["time"] >= trace["time"].max() - args.seconds]
            rows.append({"seed": record["seed"], "end": end_kind(episode), "b": last["b"].mean(),
                         "omega": last["omega"].mean(), "at_omega_floor": (last["omega"] < args.omega_floor).mean()})
    table = pd.DataFrame(rows)
    summary = table.groupby("end").agg(episodes=("b", "size"), b=("b", "mean"), omega=("omega", "mean"),
                                       at_omega_floor=("at_omega_floor", "mean"))
    print(f"last {args.seconds:g} s of each episode, mean over episodes:")
    print(summary.round(2).to_string())
    failed = table[table["end"] != "success"]
    print("failed episodes per seed:")
    print(failed.groupby(["seed", "end"])[["b", "omega", "at_omega_floor"]].mean().round(2).to_string())


if __name__ == "__main__":
    main()
