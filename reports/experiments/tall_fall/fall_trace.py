"""Why an episode ends in `fall`: the base's clearance over the terrain below it, its tilt, and what touches.

    PYTHONPATH=<worktree> .venv/bin/python reports/experiments/tall_fall/fall_trace.py POLICY_DIR TERRAIN EPISODE \
        [--last 2.0] [--every 2] [--set section.key=value ...]
    ... fall_trace.py --gait 0.6,0.4,3.141593 TERRAIN EPISODE ...   (a fixed gait instead of a policy)

The env ends an episode in `fall` when roll or pitch passes `task.fall_tilt` (rad) or the base centre comes within
`task.fall_height` (m) of the terrain directly below it. The chassis is 0.08 m thick, so at the default 0.07 its
belly is still 0.03 m above a level top when the check fires. This prints the episode's last `--last` seconds, every
`--every` control steps (0.05 s each): time (s); base x (m from the start); base height z (m, world); the terrain
height under the base centre (m); clearance = z minus that (m); roll and pitch (rad); forward velocity (m/s); the
policy's b (rad); the normal force on each leg's lower link (N); the normal force on the chassis itself (N, > 0 means
the belly or a side rests on something); which legs the elevator reflex holds open (1 = caught). A summary line says
which check ended it and the episode's lowest clearance. The episode is evaluate's (seed eval.seed + EPISODE); pass
the policy's training overrides with --set.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "ceiling"))
from episodes import checked_inputs, evaluate_episode, parse_gait  # the helper in ceiling/

from hexpipe.envs.hexapod import quat_to_roll_pitch
from hexpipe.evaluation.controllers import ControllerSpec
from hexpipe.sensors.contacts import read_contacts

CHASSIS_LINK = -1  # PyBullet's index of the base link


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("policy", help="a policy folder, or - with --gait")
    ap.add_argument("terrain")
    ap.add_argument("episode", type=int)
    ap.add_argument("--gait", help="run this fixed gait a,b,omega instead of a policy")
    ap.add_argument("--last", type=float, default=2.0, help="print the episode's last this many seconds")
    ap.add_argument("--every", type=int, default=2, help="print every N control steps (0.05 s each)")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    if a.gait is None and a.policy == "-":
        raise SystemExit("error: give a policy folder or --gait a,b,omega")
    params = checked_inputs(a.overrides, [a.terrain], [] if a.gait else [a.policy])
    spec = (ControllerSpec("best_fixed", gait=parse_gait(a.gait)) if a.gait else ControllerSpec("policy", a.policy))
    rows: list[tuple[float, float, float, float, str]] = []  # (time, clearance, roll, pitch, printed line)

    def record(env, reward, info, ended) -> None:
        pos, quat, lin, _ = env.robot.base_state()
        roll, pitch = quat_to_roll_pitch(quat)
        below = float(env.terrain.height_at(pos[:1], pos[1:2])[0])
        legs = read_contacts(env.robot.client, env.robot.body, env.robot.foot_links)[1]
        chassis = read_contacts(env.robot.client, env.robot.body, [CHASSIS_LINK])[1][0]
        caught = "".join("1" if c else "0" for c in getattr(env, "_caught", []))
        t = env.steps * env.control_dt
        line = (f"{t:5.2f} {pos[0] - env.start_xy[0]:5.2f} {pos[2]:5.3f} {below:5.3f} {pos[2] - below:6.3f} "
                f"{roll:5.2f} {pitch:5.2f} {lin[0]:5.2f} {env.cpg.params[1]:5.2f} | "
                + " ".join(f"{f:4.0f}" for f in legs) + f" | {chassis:4.0f} | {caught}")
        rows.append((t, pos[2] - below, roll, pitch, line))

    row = evaluate_episode(spec, a.terrain, a.episode, a.overrides, on_step=record)
    end = rows[-1][0]
    tail = [r for i, r in enumerate(rows) if r[0] >= end - a.last and (i % a.every == 0 or r is rows[-1])]
    low = min(rows, key=lambda r: r[1])
    task = params.task
    _, clearance, roll, pitch, _ = rows[-1]
    cause = ("tilt" if max(abs(roll), abs(pitch)) > task.fall_tilt else
             "height" if clearance < task.fall_height else "-")
    print(f"{a.terrain} episode {a.episode}: {row['termination']} at {row['distance']:.2f} m after {row['time']:.2f} s,"
          f" stall legs {row['stall_legs'] or '-'}; check that fired: {cause} (fall_height {task.fall_height} m,"
          f" fall_tilt {task.fall_tilt} rad); lowest clearance {low[1]:.3f} m at {low[0]:.2f} s")
    print("    t     x     z below  clear  roll pitch    vx     b | lower-link force (N), legs 1-6 | chassis | caught")
    print("\n".join(r[4] for r in tail))


if __name__ == "__main__":
    main()
