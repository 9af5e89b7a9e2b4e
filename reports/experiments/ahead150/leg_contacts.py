"""What holds a pinned foot: one leg's joints, targets, torques and terrain contacts, every control step (0.05 s).

    .venv/bin/python reports/experiments/ahead150/leg_contacts.py POLICY_DIR TERRAIN EPISODE LEG FROM_S TO_S [k=v ...]

LEG is the leg's index in RobotSpec's order (0 leg1 left front ... 4 leg5 left hind, 5 leg6 right hind). Columns:
time (s), the leg's oscillator y (> 0: swing), its hip yaw, shoulder and elbow angles and their targets (rad), the
torques they apply (N m; the limits are 20, 38 and 20), then each contact between one of the leg's links and the
terrain: which link, where (x from the start, z; m), the normal force (N) and the contact normal's x and z (pointing
from the terrain to the robot). The episode is evaluate's (seed eval.seed + EPISODE); pass the policy's training
overrides as section.key=value.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "ceiling"))
from episodes import checked_inputs, evaluate_episode  # the helper beside ceiling/trace.py

from hexpipe.evaluation.controllers import ControllerSpec

JOINTS = 3  # hip yaw, shoulder, elbow per leg, in PyBullet joint order


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("policy")
    ap.add_argument("terrain")
    ap.add_argument("episode", type=int)
    ap.add_argument("leg", type=int, choices=range(6))
    ap.add_argument("start", type=float)
    ap.add_argument("stop", type=float)
    ap.add_argument("overrides", nargs="*", metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    checked_inputs(a.overrides, [a.terrain], [a.policy])
    joints = list(range(a.leg * JOINTS, (a.leg + 1) * JOINTS))
    lines: list[str] = []

    def record(env, reward, info, ended) -> None:
        t = env.steps * env.control_dt
        if not a.start <= t <= a.stop:
            return
        p, client, robot, x0 = env._p, env.client, env.robot, env.start_xy[0]
        names = robot.spec.link_names
        states = p.getJointStates(robot.body, joints, physicsClientId=client)
        q = " ".join(f"{s[0]:+5.2f}" for s in states)
        target = " ".join(f"{v:+5.2f}" for v in env._targets[joints[0] : joints[-1] + 1])
        torque = " ".join(f"{s[3]:+4.0f}" for s in states)
        contacts = [
            f"{names[c[3]].split('_')[1]}@({c[5][0] - x0:.2f},{c[5][2]:.2f}) {c[9]:.0f}N "
            f"n({c[7][0]:+.1f},{c[7][2]:+.1f})"
            for c in p.getContactPoints(bodyA=robot.body, physicsClientId=client)
            if c[3] in joints and c[9] > 0.5
        ]
        lines.append(f"{t:5.2f} {env._xy[a.leg][1]:+5.2f}  {q}  {target}  {torque}  " + "; ".join(contacts))

    row = evaluate_episode(ControllerSpec("policy", a.policy), a.terrain, a.episode, a.overrides, on_step=record)
    print(f"{a.terrain} episode {a.episode}: {row['termination']} at {row['distance']:.2f} m; leg index {a.leg}")
    print("    t     y  yaw   shldr elbow  target yaw/shldr/elbow  torque (N m)  contacts (link@(x,z) force normal)")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
