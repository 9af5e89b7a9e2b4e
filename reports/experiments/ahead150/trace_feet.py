"""One evaluate episode of a policy, every control step (0.05 s): the base, the CPG and where three feet are.

    .venv/bin/python reports/experiments/ahead150/trace_feet.py POLICY_DIR TERRAIN EPISODE FROM_S TO_S [k=v ...]

Columns: time (s), base x from the start (m), base height (m, world), pitch (rad, positive nose-down), b and omega
(the policy's), the lift floors `cpg.lift_follows`' trail gives the middle and the hind legs (rad), then x, y, z (m,
x from the start) of leg5 (left hind), leg6 (right hind) and leg3 (left middle). Rows from FROM_S to TO_S (s). The
episode is evaluate's (seed eval.seed + EPISODE); pass the policy's training overrides as section.key=value.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "ceiling"))
from episodes import checked_inputs, evaluate_episode  # the helper beside ceiling/trace.py

from hexpipe.envs.hexapod import quat_to_roll_pitch
from hexpipe.evaluation.controllers import ControllerSpec

FEET = {"h5": 4, "h6": 5, "m3": 2}  # index into Robot.foot_positions(), RobotSpec's leg order


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("policy")
    ap.add_argument("terrain")
    ap.add_argument("episode", type=int)
    ap.add_argument("start", type=float)
    ap.add_argument("stop", type=float)
    ap.add_argument("overrides", nargs="*", metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    checked_inputs(a.overrides, [a.terrain], [a.policy])
    rows: list[tuple[float, ...]] = []

    def record(env, reward, info, ended) -> None:
        pos, quat, _, _ = env.robot.base_state()
        feet = env.robot.foot_positions()
        floors = env.trail.floor(env._last_x) if env.trail is not None else [0.0] * 6
        x0 = env.start_xy[0]
        rows.append((env.steps * env.control_dt, pos[0] - x0, pos[2], quat_to_roll_pitch(quat)[1],
                     env.cpg.params[1], env.cpg.params[2], floors[2], floors[4],
                     *(v for i in FEET.values() for v in (feet[i][0] - x0, feet[i][1], feet[i][2]))))

    row = evaluate_episode(ControllerSpec("policy", a.policy), a.terrain, a.episode, a.overrides, on_step=record)
    print(f"{a.terrain} episode {a.episode}: {row['termination']} at {row['distance']:.2f} m, "
          f"stall legs {row['stall_legs']}")
    names = ("t", "x", "z", "pitch", "b", "omega", "flMid", "flHnd", *(leg + axis for leg in FEET for axis in "xyz"))
    print(" ".join(f"{name:>5}" for name in names))
    for values in rows:
        if a.start <= values[0] <= a.stop:
            print(" ".join(f"{v:5.2f}" for v in values))


if __name__ == "__main__":
    main()
