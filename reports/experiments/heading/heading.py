"""The heading reflex at run time: evaluate's episodes of fixed gaits or trained policies at several
`sim.heading_gain` values, with how far each episode's base turned off the course.

    PYTHONPATH=. .venv/bin/python reports/experiments/heading/heading.py --gain 0 --gain 1 \
        [--policy DIR ...] [--gait A,B,OMEGA ...] [--terrain T ...] [--episodes 10] [--workers 2] \
        [--set section.key=value ...] [--csv episodes.csv]

Each arm is one gain; the episodes are evaluate's (seed eval.seed + index), so arm 0 of a policy is what its sweep
trial scored when the trial trained at gain 0. Prints, per controller and gain: successes, the mean time to goal (s)
and cost of transport of the episodes every arm finished, the mean and the largest |yaw| (rad) at any step, and
how many episodes turned more than 0.5 rad off the course; then successes per terrain, and the failures' end
(distance in m, final yaw in rad).
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "ceiling"))
from episodes import add_episode_options, checked_inputs, evaluate_episode, parse_gait  # the helper in ceiling/

from hexpipe.evaluation.controllers import ControllerSpec
from hexpipe.sensors.heightmap import quat_to_yaw

SUITE = ("flat", "single_block", "extra_blocks", "wide_block", "rough", "low_block", "tall_block", "steps_up",
         "block_near", "block_far")
TURNED = 0.5  # rad off the course: an episode that turns this far has lost its heading


def _one(job: tuple[str, ControllerSpec, float, str, int, tuple[str, ...]]) -> dict:
    name, controller, gain, terrain, index, overrides = job
    yaws: list[float] = []

    def record(env, reward, info, ended) -> None:
        yaws.append(quat_to_yaw(env.robot.base_state()[1]))

    row = evaluate_episode(controller, terrain, index, (*overrides, f"sim.heading_gain={gain}"), on_step=record)
    return {"controller": name, "gain": gain, "terrain": terrain, "episode": index, "success": bool(row["success"]),
            "distance": row["distance"], "time": row["time"], "cost_of_transport": row["cost_of_transport"],
            "max_abs_yaw": max(abs(y) for y in yaws), "final_yaw": yaws[-1]}


def summary(frame: pd.DataFrame) -> pd.DataFrame:
    """Per controller and gain; time and cost over the episodes that every gain of that controller finished."""
    done = frame.pivot_table(index=["controller", "terrain", "episode"], columns="gain", values="success")
    both = done[done.all(axis=1)].index
    keyed = frame.set_index(["controller", "terrain", "episode"])
    shared = keyed[keyed.index.isin(both)].reset_index()
    out = frame.groupby(["controller", "gain"]).agg(
        success=("success", "sum"), episodes=("success", "size"), mean_abs_yaw=("max_abs_yaw", "mean"),
        worst_yaw=("max_abs_yaw", "max"), turned=("max_abs_yaw", lambda s: int((s > TURNED).sum())))
    out["time_shared"] = shared.groupby(["controller", "gain"])["time"].mean()
    out["cot_shared"] = shared.groupby(["controller", "gain"])["cost_of_transport"].mean()
    out["shared"] = shared.groupby(["controller", "gain"]).size()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gain", dest="gains", type=float, action="append", required=True)
    ap.add_argument("--policy", dest="policies", action="append", default=[])
    ap.add_argument("--gait", dest="gaits", action="append", default=[])
    add_episode_options(ap, episodes=10)
    a = ap.parse_args()
    terrains = a.terrains or list(SUITE)
    checked_inputs(a.overrides, terrains, a.policies)
    controllers = [(p, ControllerSpec("policy", p)) for p in a.policies]
    controllers += [(g, ControllerSpec("best_fixed", gait=parse_gait(g))) for g in a.gaits]
    if not controllers:
        raise SystemExit("error: name at least one --policy or --gait")
    jobs = [(name, spec, gain, t, i, tuple(a.overrides)) for name, spec in controllers for gain in a.gains
            for t in terrains for i in range(a.episodes)]
    with ProcessPoolExecutor(a.workers) as pool:
        frame = pd.DataFrame(list(pool.map(_one, jobs)))
    if a.csv:
        frame.to_csv(a.csv, index=False)
    pd.set_option("display.width", 200)
    print(summary(frame).round(3).to_string())
    print()
    print(frame.pivot_table(index=["controller", "gain"], columns="terrain", values="success", aggfunc="sum")
          .astype(int).to_string())
    fails = frame[~frame.success]
    print("\nfailures: controller, gain, terrain, episode, distance (m), final yaw (rad)")
    for r in fails.itertuples():
        print(f"  {r.controller} {r.gain:g} {r.terrain} {r.episode} {r.distance:.2f} {r.final_yaw:+.2f}")


if __name__ == "__main__":
    main()
