"""The lift_vote ensembles against their fixed gait and their own members, on the suite's 10 episodes a terrain.

Reads probe.py's rows (suite10.csv) and the members' sweep episodes (episodes 0-9 of each terrain are the same
layouts and starts), and applies evaluate's verdict (success within 5 points, no slower, cheaper) per terrain:

    .venv/bin/python reports/experiments/ensemble/verdict.py [reports/experiments/ensemble/suite10.csv]
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

from hexpipe.evaluation.metrics import summarise, verdict

ENSEMBLES = {  # name: (sweep folder, condition, member seeds), as registered in the experiments README
    "stride_odd": ("reports/sweeps/stride_reflex", "pinned_stride", (1, 1001, 2001)),
    "stride_even": ("reports/sweeps/stride_reflex", "pinned_stride", (2, 1002, 2002)),
    "long_odd": ("reports/sweeps/long_stride", "long_stride", (1, 1001, 2001)),
    "long_even": ("reports/sweeps/long_stride", "long_stride", (2, 1002, 2002)),
}
FIXED = "best_fixed"


def _beaten(rows: pd.DataFrame, learned: str, terrains: list[str]) -> dict[str, bool]:
    table = summarise(rows, terrains, [learned, FIXED])
    return {call.terrain: call.beats for call in verdict(table, terrains, learned)}


def main() -> int:
    path = Path(sys.argv[1] if len(sys.argv) > 1 else "reports/experiments/ensemble/suite10.csv")
    if not path.is_file():
        print(f"error: {path} is missing; run probe.py with --csv first", file=sys.stderr)
        return 1
    ours = pd.read_csv(path)
    terrains = list(dict.fromkeys(ours["terrain"]))
    for name, (sweep, condition, seeds) in ENSEMBLES.items():
        mine = ours[ours["ensemble"] == name]
        if mine.empty:
            continue
        episodes = pd.read_csv(Path(sweep) / "episodes.csv")
        episodes = episodes[episodes["terrain"].isin(terrains) & (episodes["episode"] < mine["episode"].max() + 1)]
        trials = [f"{condition}-seed{s}" for s in seeds]
        fixed = episodes[(episodes["trial"] == trials[0]) & (episodes["controller"] == FIXED)]
        members = {t: episodes[(episodes["trial"] == t) & (episodes["controller"] == "policy")] for t in trials}
        beaten = {name: _beaten(pd.concat([mine, fixed]), name, terrains)}  # probe.py names the controller
        beaten |= {t: _beaten(pd.concat([members[t].assign(controller=t), fixed]), t, terrains) for t in trials}
        board = pd.DataFrame(beaten).astype(int)
        success = pd.DataFrame({who: rows.groupby("terrain")["success"].mean()
                                for who, rows in [(name, mine), *members.items(), (FIXED, fixed)]}).loc[terrains]
        won = {who: rows[rows["success"].astype(bool)].groupby("terrain")[["time", "cost_of_transport"]].mean()
               for who, rows in [(name, mine), (FIXED, fixed)]}
        print(f"\n{name}: {', '.join(trials)} ({sweep})")
        print("success")
        print(success.round(2).to_string())
        print("time (s) and cost of transport over successes")
        print(pd.concat(won, axis=1).loc[terrains].round(2).to_string())
        print("beats the fixed gait (1)")
        print(board.to_string())
        print("terrains beaten: " + ", ".join(f"{who} {n}" for who, n in board.sum().items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
