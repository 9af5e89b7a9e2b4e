"""One evaluate episode of a policy, every N control steps: where the base is and where it faces.

    PYTHONPATH=. .venv/bin/python reports/experiments/heading/trace_yaw.py POLICY_DIR TERRAIN EPISODE \
        [--every 20] [--set section.key=value ...]

Columns: time (s); base x and y from the start (m); height (m, world); yaw, roll, pitch (rad; yaw 0 faces the
course, +x, negative is turned right); forward velocity (m/s, world x); the policy's b (rad) and omega (rad/s); the
summed normal force on each leg's lower link (N); and which legs the elevator reflex holds open (1 = caught). The
episode is evaluate's (seed eval.seed + EPISODE); pass the policy's training overrides with --set.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "ceiling"))
from episodes import checked_inputs, evaluate_episode  # the helper in ceiling/

from hexpipe.envs.hexapod import quat_to_roll_pitch
from hexpipe.evaluation.controllers import ControllerSpec
from hexpipe.sensors.contacts import read_contacts
from hexpipe.sensors.heightmap import quat_to_yaw


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("policy")
    ap.add_argument("terrain")
    ap.add_argument("episode", type=int)
    ap.add_argument("--every", type=int, default=20, help="print every N control steps (0.05 s each)")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    checked_inputs(a.overrides, [a.terrain], [a.policy])
    rows: list[str] = []

    def record(env, reward, info, ended) -> None:
        if env.steps % a.every and not ended:
            return
        pos, quat, lin, _ = env.robot.base_state()
        roll, pitch = quat_to_roll_pitch(quat)
        force = read_contacts(env.robot.client, env.robot.body, env.robot.foot_links)[1]
        caught = "".join("1" if c else "0" for c in getattr(env, "_caught", []))
        x, y = pos[:2] - env.start_xy
        rows.append(f"{env.steps * env.control_dt:5.2f} {x:5.2f} {y:5.2f} {pos[2]:5.3f} {quat_to_yaw(quat):5.2f} "
                    f"{roll:5.2f} {pitch:5.2f} {lin[0]:5.2f} "
                    f"{env.cpg.params[1]:5.2f} {env.cpg.params[2]:5.2f} | " + " ".join(f"{f:4.0f}" for f in force)
                    + f" | {caught}")

    row = evaluate_episode(ControllerSpec("policy", a.policy), a.terrain, a.episode, a.overrides, on_step=record)
    print(f"{a.terrain} episode {a.episode}: {row['termination']} at {row['distance']:.2f} m after "
          f"{row['time']:.2f} s, stall legs {row['stall_legs']}")
    print("    t     x     y     z   yaw  roll pitch    vx     b omega | lower-link force (N), legs 1-6 | caught")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
