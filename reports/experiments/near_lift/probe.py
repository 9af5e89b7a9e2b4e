"""Run-time arms of a reflex setting on trained policies and a fixed gait: evaluate's episodes of a few terrains
under each arm's extra --set overrides, with success, time and cost of transport per arm, controller and terrain.

    .venv/bin/python reports/experiments/near_lift/probe.py POLICY_DIR... --gait 0.4,0.4,3.141593
        --arm "off:" --arm "near:task.lift_reflex=true;task.lift_reflex_zone=[0.2,0.7]"
        [--terrain single_block --terrain extra_blocks] [--episodes 20] [--set section.key=value ...]

--set gives the settings the policies were trained under; each arm adds its own on top. The fixed gait gets the
same arm, since a reflex is part of the env every controller walks in. Episode i runs with seed eval.seed + i, so
episodes 0-9 are a sweep trial's own.
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ceiling"))
from episodes import add_episode_options, checked_inputs, evaluate_episode, parse_gait  # the helpers in ../ceiling

from hexpipe.evaluation.controllers import ControllerSpec


def _one(job: tuple[str, ControllerSpec, str, int, tuple[str, ...]]) -> dict:
    arm, controller, terrain, index, overrides = job
    row = evaluate_episode(controller, terrain, index, overrides)
    return {"arm": arm, "controller": controller.policy_dir or "fixed", "terrain": terrain, "episode": index,
            "success": bool(row["success"]), "time": row["time"], "cost_of_transport": row["cost_of_transport"],
            "distance": row["distance"]}


def _arm(text: str) -> tuple[str, list[str]]:
    name, _, sets = text.partition(":")
    if not name:
        raise SystemExit(f"error: arm {text!r} is not NAME:overrides (overrides joined by ';', may be empty)")
    return name, [s for s in sets.split(";") if s]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("policies", nargs="*")
    ap.add_argument("--gait", help="a fixed gait a,b,omega walked beside the policies")
    ap.add_argument("--arm", dest="arms", action="append", required=True, metavar="NAME:SETS")
    add_episode_options(ap, episodes=20)
    a = ap.parse_args()
    terrains = a.terrains or ["single_block", "extra_blocks"]
    arms = [_arm(text) for text in a.arms]
    for _, sets in arms:  # a bad key, terrain or policy under any arm: one line, before any episode
        checked_inputs(a.overrides + sets, terrains, a.policies)
    controllers = [ControllerSpec("policy", p) for p in a.policies]
    if a.gait:
        controllers.append(ControllerSpec("fixed", gait=parse_gait(a.gait)))
    jobs = [(name, c, t, i, tuple(a.overrides + sets)) for name, sets in arms for c in controllers
            for t in terrains for i in range(a.episodes)]
    with ProcessPoolExecutor(a.workers) as pool:
        rows = pd.DataFrame(list(pool.map(_one, jobs, chunksize=4)))
    if a.csv:
        rows.to_csv(a.csv, index=False)
    rows["controller"] = rows["controller"].map(lambda c: Path(c).parent.name if c != "fixed" else c)
    won = rows[rows["success"]]
    table = rows.groupby(["terrain", "controller", "arm"]).agg(success=("success", "mean")).join(
        won.groupby(["terrain", "controller", "arm"])[["time", "cost_of_transport"]].mean()).unstack("arm")
    print(f"{len(a.policies)} policies and {'a fixed gait ' + a.gait if a.gait else 'no fixed gait'}, "
          f"{a.episodes} episodes each; time and cost over successes")
    print(table.round(2).to_string())
    print("\nmean over the policies")
    policies = rows[rows["controller"] != "fixed"]
    print(policies.groupby(["terrain", "arm"]).agg(success=("success", "mean")).join(
        won[won["controller"] != "fixed"].groupby(["terrain", "arm"])[["time", "cost_of_transport"]].mean())
        .round(3).to_string())


if __name__ == "__main__":
    main()
