"""Where each lost suite episode of a sweep's condition ends: a replay of evaluate's episode with the trial's own
policy and overrides, printing the base's end position and yaw, so that a loss that is a turn off the course
(|yaw| > TURNED at the end) is told from a stall at a face.

    PYTHONPATH=<worktree> .venv/bin/python reports/experiments/heading/lost_yaw.py reports/sweeps/head150 \
        --condition head150 [--data data/sweeps/head150]

A sweep's report folder gives each trial's episodes and overrides (result.json); its policy is read from the
sweep's data folder (`data/sweeps/<sweep name>/<trial>/ppo`). Each replay's outcome must repeat the trial's: a
replay that differs is printed as such (the replay is not the evaluation then) and exits 1. Flat ground is not in
the suite and is skipped.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "ceiling"))
from episodes import evaluate_episode  # the helper in ceiling/

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "select"))
from pipelines import load_records  # select/pipelines.py: a sweep's complete trial records

from hexpipe.evaluation.controllers import ControllerSpec
from hexpipe.sensors.heightmap import quat_to_yaw

TURNED = 1.0  # rad at the end of the episode: a base this far off the course walks more sideways than forwards


def lost_episodes(records: list[dict]) -> list[tuple[dict, dict]]:
    """(trial record, lost suite episode) for every lost policy episode off flat ground."""
    return [(record, ep) for record in records for ep in record["episodes"]
            if ep["controller"] == "policy" and ep["terrain"] != "flat" and not ep["success"]]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("report", type=Path, help="the sweep's report folder (reports/sweeps/NAME)")
    ap.add_argument("--condition", required=True)
    ap.add_argument("--data", type=Path, help="the sweep's data folder (default data/sweeps/NAME)")
    a = ap.parse_args()
    if not a.report.is_dir():
        raise SystemExit(f"error: {a.report} is not a folder")
    data = a.data or Path("data/sweeps") / a.report.name
    records = load_records([a.report], a.condition)
    lost = lost_episodes(records)
    print(f"{len(lost)} lost suite episodes of {a.condition} over {len(records)} complete trials in {a.report}")
    print(f"{'trial':<22} {'terrain':<13} ep  distance  end x   end y  end yaw  max|yaw|  stall legs        kind")
    mismatch = 0
    for result, ep in lost:
        policy = data / result["trial"] / "ppo"
        if not policy.is_dir():
            raise SystemExit(f"error: {policy} is missing (the trial's policy; pass --data)")
        track = {"max": 0.0}

        def record(env, _reward, _info, _ended, track=track) -> None:
            pos, quat, _, _ = env.robot.base_state()
            yaw = quat_to_yaw(quat)
            track.update(x=float(pos[0] - env.start_xy[0]), y=float(pos[1] - env.start_xy[1]), yaw=yaw,
                         max=max(track["max"], abs(yaw)))

        row = evaluate_episode(ControllerSpec("policy", str(policy)), ep["terrain"], ep["episode"],
                               result["overrides"], on_step=record)
        same = bool(row["success"]) == bool(ep["success"]) and abs(row["distance"] - ep["distance"]) < 1e-6
        mismatch += not same
        kind = "turn" if abs(track["yaw"]) > TURNED else "stall"
        print(f"{result['trial']:<22} {ep['terrain']:<13} {ep['episode']:>2}  {ep['distance']:8.2f}  "
              f"{track['x']:5.2f}  {track['y']:6.2f}  {track['yaw']:+7.2f}  {track['max']:8.2f}  "
              f"{ep['stall_legs'] or '-'!s:<16}  {kind if same else 'REPLAY DIFFERS'}")
    if mismatch:
        print(f"{mismatch} replays differ from their trial's outcome")
        raise SystemExit(1)


if __name__ == "__main__":
    main()
