"""Where a policy lifts on single_block, measured at the body (the report's adaptation figure) and at the front feet.

The evaluation's adaptation figure is the mean b while the *base* is in the 0.3 m before the face, against b on
open ground. The front feet lead the base by 0.47 m, so with `cpg.lift_follows` (the middle and hind legs carry the
front legs' lift over the block) the lift a policy needs is the one it commands while the *front feet* approach
the face: by the time the base is 0.3 m from it, the front legs are already on the block. This prints both.

    .venv/bin/python reports/experiments/front_feet_lift.py /work/wt-follow/data/sweeps/follow/floors_follow-seed{0,1}

Each argument is a sweep trial's data folder (`data/sweeps/NAME/TRIAL`, holding eval/cpg_traces.csv.gz).
`--column b` reads the policy's own b instead of the swing lift (they differ only under `task.lift_reflex`).
"""

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

from hexpipe.config import SimConfig
from hexpipe.evaluation.episodes import TRACE_COLUMNS, lift_before_and_away
from hexpipe.sim.robot import RobotSpec
from hexpipe.sim.terrain.recipes import SCENARIOS

TERRAIN = "single_block"


def lifts(traces: Path, lead: float, column: str = "lift") -> pd.DataFrame:
    """Per policy episode on TERRAIN: the lift before the face at the body, at the front feet, and on open ground;
    column "lift" is the front legs' swing lift (b, or the reflex's when higher), "b" the policy's own b."""
    block = SCENARIOS[TERRAIN].boxes[0]
    at_body = [(block.face, block.face + block.depth)]
    at_feet = [(block.face - lead, block.face + block.depth - lead)]
    frame = pd.read_csv(traces)
    if "lift" not in frame:  # traces from before the lift reflex: the front legs swung with b
        frame["lift"] = frame["b"]
    if "stride" not in frame:  # traces from before the stride reflex: the legs swung with a
        frame["stride"] = frame["a"]
    frame["lift"] = frame[column]  # the column lift_before_and_away reads
    rows = []
    for episode, trace in frame[(frame.terrain == TERRAIN) & (frame.controller == "policy")].groupby("episode"):
        cpg = trace[list(TRACE_COLUMNS)].to_numpy(dtype=np.float32)
        before_body, open_ground = lift_before_and_away(cpg, at_body)
        before_feet, _ = lift_before_and_away(cpg, at_feet)
        rows.append({"episode": episode, "body": before_body, "front_feet": before_feet, "open": open_ground})
    return pd.DataFrame(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trials", nargs="+", type=Path, help="data/sweeps/NAME/TRIAL folders")
    parser.add_argument("--column", choices=("lift", "b"), default="lift",
                        help="the swing lift (default) or the policy's own b")
    args = parser.parse_args()
    # the front feet's neutral stance point, ahead of the base (as in hexpipe.sim.lift_trail.foot_lags)
    spec, reach = RobotSpec(), SimConfig().stance_reach
    lead = max((leg.radius + reach) * math.cos(leg.angle) for leg in spec.legs)
    rows = []
    for trial in args.trials:
        traces = trial / "eval" / "cpg_traces.csv.gz"
        if not traces.is_file():
            raise SystemExit(f"error: {trial} is not a sweep trial folder (data/sweeps/NAME/TRIAL): missing {traces}")
        means = lifts(traces, lead, args.column).mean()
        rows.append({"trial": trial.name, "b before (body)": means["body"],
                     "b before (front feet)": means["front_feet"], "b open": means["open"]})
    table = pd.DataFrame(rows).set_index("trial")
    table["lift (body)"] = table["b before (body)"] - table["b open"]
    table["lift (front feet)"] = table["b before (front feet)"] - table["b open"]
    print(f"{TERRAIN}, policy episodes; the front feet lead the base by {lead:.2f} m; column {args.column!r}, rad")
    print(table.round(3).to_string())
    print("mean over trials:")
    print(table.mean().round(3).to_string())


if __name__ == "__main__":
    main()
