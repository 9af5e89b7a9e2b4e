"""Where the wide block stops a policy: does a hind foot stay planted against the face while the CPG cycles?

    .venv/bin/python reports/experiments/ahead150/pinned_feet.py [POLICY_DIR[=LABEL] ...] [--gait A,B,OMEGA ...]
        [--terrain wide_block ...] [--episodes 0,1,...] [--face 1.0] [--band 0.06] [--set k=v ...]

For each policy or fixed gait (--gait, held for the episode, as the verdict's grid holds it) and evaluate episode
(seed eval.seed + index, so the outcome matches the sweep's results.csv), it tracks the two hind feet (leg5 left,
leg6 right) every control step and reports, per episode: the outcome, where the base stopped, and for each hind foot
the longest time (s) it stayed "pinned": its centre within `band` m short of the face (x in [face - band, face]) and
below 5 cm, i.e. on the ground at the face's foot, not on the block. A foot that swings over stays there for one
stance at most (at omega pi, a stance lasts 1 s; at 1.5 pi, 0.67 s). Pass the policy's training overrides with
--set, as in the sweep's condition.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "ceiling"))
from episodes import checked_inputs, evaluate_episode  # the helper beside ceiling/trace.py

from hexpipe.evaluation.controllers import ControllerSpec

HIND = {"leg5": 4, "leg6": 5}  # index into Robot.foot_positions(), RobotSpec's leg order
LOW = 0.05  # m: a foot centre below this is on the ground, not on a 0.1 m block


def longest_run(flags: list[bool], dt: float) -> float:
    """The longest stretch of consecutive True flags, in s (dt per flag)."""
    best = run = 0
    for flag in flags:
        run = run + 1 if flag else 0
        best = max(best, run)
    return best * dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("policies", nargs="*", help="POLICY_DIR or POLICY_DIR=LABEL")
    ap.add_argument("--gait", dest="gaits", action="append", default=[], metavar="A,B,OMEGA", help="a fixed gait")
    ap.add_argument("--terrain", dest="terrains", action="append", help="repeatable (default wide_block)")
    ap.add_argument("--episodes", default="0,1,2,3,4,5,6,7,8,9", help="comma-separated evaluate episode indices")
    ap.add_argument("--face", type=float, default=1.0, help="x of the block's near face from the start (m)")
    ap.add_argument("--band", type=float, default=0.06, help="how far short of the face a foot counts (m)")
    ap.add_argument("--long", type=float, default=1.0, help="a pin at least this long (s) counts in the summary")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    try:
        episodes = [int(e) for e in a.episodes.split(",")]
    except ValueError:
        raise SystemExit(f"error: --episodes {a.episodes!r} is not a comma-separated list of integers") from None
    specs = [p.partition("=")[::2] for p in a.policies]
    terrains = a.terrains or ["wide_block"]
    checked_inputs(a.overrides, terrains, [path for path, _ in specs])
    controllers = [(label or Path(path).parent.name, ControllerSpec("policy", path)) for path, label in specs]
    for text in a.gaits:
        try:
            gait = tuple(float(v) for v in text.split(","))
        except ValueError:
            gait = ()
        if len(gait) != 3:
            raise SystemExit(f"error: --gait {text!r} is not A,B,OMEGA (three numbers)")
        controllers.append((f"gait {text}", ControllerSpec("best_fixed", gait=gait)))
    if not controllers:
        raise SystemExit("error: name a policy folder or a --gait")
    pins = " ".join(f"{leg}_pinned_s" for leg in HIND)
    print(f"{'controller':<22} {'terrain':<13} {'ep':>3} {'outcome':<8} {'x_end':>6} {pins}")
    tally: list[tuple[str, bool, bool]] = []  # (terrain, stuck, pinned at least --long) per episode
    for label, spec in controllers:
        for terrain, episode in ((t, e) for t in terrains for e in episodes):
            flags: dict[str, list[bool]] = {leg: [] for leg in HIND}
            dt = [0.0]

            def record(env, reward, info, ended, flags=flags, dt=dt) -> None:
                feet = env.robot.foot_positions()
                dt[0] = env.control_dt
                for leg, i in HIND.items():
                    x, z = feet[i][0] - env.start_xy[0], feet[i][2]
                    flags[leg].append(a.face - a.band <= x <= a.face and z < LOW)

            row = evaluate_episode(spec, terrain, episode, a.overrides, on_step=record)
            pinned = " ".join(f"{longest_run(flags[leg], dt[0]):>12.2f}" for leg in HIND)
            print(f"{label:<22} {terrain:<13} {episode:>3} {row['termination']:<8} {row['distance']:>6.2f} "
                  f"{pinned}", flush=True)
            longest = max(longest_run(flags[leg], dt[0]) for leg in HIND)
            tally.append((terrain, row["termination"] == "stuck", longest >= a.long))
    for terrain in terrains if len(terrains) > 1 else []:
        stuck = [pin for t, s, pin in tally if s and t == terrain]
        arrived = [pin for t, s, pin in tally if not s and t == terrain]
        print(f"{terrain}: a hind foot pinned >= {a.long:.2f} s in {sum(stuck)} of {len(stuck)} stuck episodes and in "
              f"{sum(arrived)} of {len(arrived)} others")
    stuck = [pin for _, s, pin in tally if s]
    arrived = [pin for _, s, pin in tally if not s]
    print(f"summary over {len(tally)} episodes: a hind foot pinned >= {a.long:.2f} s in {sum(stuck)} of "
          f"{len(stuck)} stuck episodes and in {sum(arrived)} of {len(arrived)} others")


if __name__ == "__main__":
    main()
