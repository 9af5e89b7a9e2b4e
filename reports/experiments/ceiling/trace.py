"""One evaluate episode of a policy, every 0.25 s: where the base is and what the CPG does as it stalls.

    .venv/bin/python reports/experiments/ceiling/trace.py POLICY_DIR TERRAIN EPISODE [--from X] [--set k=v ...]

Columns: time (s), base distance from the start (m), base height above the terrain under it (m), pitch (rad,
positive nose-down), forward velocity (m/s), a, b, omega, b's rate (rad/s) and the step's reward. The episode is
evaluate's (seed eval.seed + EPISODE), deterministic; rows start where the base passes --from (m). Pass the
policy's own training overrides with --set (a `ceil60` policy needs `--set "cpg.upper=[0.4,0.6,6.283185]"`).
"""

from __future__ import annotations

import argparse

from episodes import checked_inputs, evaluate_episode  # the helper beside this script

from hexpipe.envs.hexapod import quat_to_roll_pitch
from hexpipe.evaluation.controllers import ControllerSpec

EVERY = 5  # control steps between rows (0.25 s at 20 Hz)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("policy")
    ap.add_argument("terrain")
    ap.add_argument("episode", type=int)
    ap.add_argument("--from", dest="start", type=float, default=0.0)
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    checked_inputs(a.overrides, [a.terrain], [a.policy])
    rows: list[tuple[float, ...]] = []

    def record(env, reward, info, ended) -> None:
        pos, quat, lin, _ = env.robot.base_state()
        below = float(env.terrain.height_at(pos[:1], pos[1:2])[0])
        pitch = quat_to_roll_pitch(quat)[1]
        rows.append((env.steps * env.control_dt, pos[0] - env.start_xy[0], pos[2] - below, pitch, lin[0],
                     *env.cpg.params, env.cpg.rates[1], reward))

    row = evaluate_episode(ControllerSpec("policy", a.policy), a.terrain, a.episode, a.overrides, on_step=record)
    print(f"{a.terrain} episode {a.episode}: {row['termination']} at {row['distance']:.2f} m after {row['time']} s, "
          f"stall legs {row['stall_legs']}")
    print("    t      x  height  pitch     vx      a      b  omega  b_rate  reward")
    for values in rows[::EVERY]:
        if values[1] >= a.start:
            print(" ".join(f"{v:6.2f}" for v in values))


if __name__ == "__main__":
    main()
