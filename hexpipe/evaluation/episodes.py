"""One evaluation episode: reset(seed), step the controller until terminated or truncated, optionally log it to
MCAP and film it. Runs in a worker process; everything it needs travels in a small picklable `EpisodeJob`."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from hexpipe.config import Params
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.envs.rewards import FAILURES, cost_of_transport
from hexpipe.evaluation.controllers import ControllerSpec, build, gait_label
from hexpipe.evaluation.suite import Scenario

StepHook = Callable[[HexapodEnv, float, dict[str, Any], bool], None]
# s, m, rad, rad, rad/s, rad, rad: the CPG parameters, then the lift the front legs swing with (b, or the lift
# reflex's when that is higher: `HexapodEnv.lift`), which the lift statistics read, and the stride the legs swing with
# (a, or the stride reflex's when that is shorter: `HexapodEnv.stride`)
TRACE_COLUMNS = ("time", "distance", "a", "b", "omega", "lift", "stride")
# The lift statistics, by the body's forward distance (m from the start). "Before the face": the last BEFORE_FACE
# before a block's start, where an adaptive gait must be lifting (issue 10's adaptation measure). "Open ground":
# farther than NEAR_BEFORE before any block (the front feet reach about FRONT_REACH ahead of the base and a policy
# may start lifting early) and NEAR_AFTER past its end (the rear legs are still on it).
FRONT_REACH = 0.45  # m ahead of the base: where the front feet are (the diagnosis scripts place a face by it)
BEFORE_FACE = 0.3
NEAR_BEFORE, NEAR_AFTER = 1.0, 0.5
# A foot "at a face" when an episode ends stuck or fallen: its centre at most FOOT_BEFORE_FACE before a block's face
# (the foot's sphere is 0.02 m) or FOOT_ON_EDGE past it (caught on the edge). Which legs they are tells a front leg
# that never lifted from a hind leg that meets a face the body has long passed.
FOOT_BEFORE_FACE, FOOT_ON_EDGE = 0.08, 0.03
LEG_GROUPS = ("front", "middle", "hind")


@dataclass(frozen=True)
class EpisodeJob:
    scenario: Scenario
    controller: ControllerSpec
    index: int  # episode number within (terrain, controller); the seed is eval.seed + index
    seed: int
    mcap: Path | None = None  # log the episode here
    video: Path | None = None  # film it here


@dataclass
class EpisodeResult:
    job: EpisodeJob
    row: dict[str, Any]  # one line of results.csv
    trace: np.ndarray  # (steps + 1, len(TRACE_COLUMNS)) float32: the CPG parameters against time and distance
    obstacles: list[tuple[float, float]] = field(default_factory=list)  # x-extents of blocks/bumps (m from start)
    feet: np.ndarray | None = None  # (steps + 1, legs) bool foot contact (episode 0 only): the gait diagram's data


def _box_spans(env: HexapodEnv) -> list[tuple[float, float]]:
    """Forward extents (m, from the start) of every box (block, step) of the realised terrain."""
    x0 = float(env.start_xy[0])
    spans = []
    for box in env.terrain.boxes:
        half = 0.5 * (abs(math.cos(box.yaw)) * box.size[0] + abs(math.sin(box.yaw)) * box.size[1])
        spans.append((box.center[0] - half - x0, box.center[0] + half - x0))
    return spans


def _obstacles(env: HexapodEnv) -> list[tuple[float, float]]:
    """Forward extents (m, from the start) of every box and height field of the realised terrain."""
    x0 = float(env.start_xy[0])
    return _box_spans(env) + [(hf.extent[0][0] - x0, hf.extent[0][1] - x0) for hf in env.terrain.heightfields]


def legs_at_faces(foot_x: np.ndarray, groups: list[str], faces: list[float]) -> str:
    """The leg groups (front, middle, hind, joined by '+') with a foot at a face (see FOOT_BEFORE_FACE), or 'none'.

    foot_x: each foot's forward position (m, from the start); groups: each leg's group; faces: block faces (m)."""
    at = {g for x, g in zip(foot_x, groups, strict=True)
          if any(f - FOOT_BEFORE_FACE <= x <= f + FOOT_ON_EDGE for f in faces)}
    return "+".join(g for g in LEG_GROUPS if g in at) or "none"


def _stall_legs(env: HexapodEnv, termination: str | None) -> str:
    """For an episode that ended stuck or fallen, which legs stood at a block face ('' otherwise)."""
    if termination not in FAILURES:
        return ""
    foot_x = env.robot.foot_positions()[:, 0] - float(env.start_xy[0])
    faces = [lo for lo, _ in _box_spans(env)]
    return legs_at_faces(foot_x, [leg.group for leg in env.robot_spec.legs], faces)


def lift_before_and_away(trace: np.ndarray, obstacles: list[tuple[float, float]]) -> tuple[float, float]:
    """Mean lift (rad; b, or the lift reflex's when higher) over the steps in the BEFORE_FACE before a block and
    over the steps on open ground; NaN where there were none (no block, or stuck before reaching the window).

    An adaptive gait lifts its feet before blocks and lowers them elsewhere; a fixed gait without the lift reflex has
    the same lift in both.
    """
    x, b = trace[:, TRACE_COLUMNS.index("distance")], trace[:, TRACE_COLUMNS.index("lift")]
    before, near = np.zeros(len(x), dtype=bool), np.zeros(len(x), dtype=bool)
    for lo, hi in obstacles:
        before |= (x >= lo - BEFORE_FACE) & (x < lo)
        near |= (x >= lo - NEAR_BEFORE) & (x <= hi + NEAR_AFTER)
    return tuple(float(b[mask].mean()) if mask.any() else math.nan for mask in (before, ~near))


def _feet(env: HexapodEnv) -> np.ndarray:
    """Which feet touch the ground now (the contacts sensor's first row), legs in the robot's order."""
    return env.sense(("contacts",))["contacts"][0] > 0


def _trace_row(info: dict[str, Any]) -> list[float]:
    return [info["time"], info["distance"], *map(float, info["cpg"]), info["lift"], info["stride"]]


def run_episode(params: Params, job: EpisodeJob, on_step: StepHook | None = None) -> EpisodeResult:
    """Roll out one episode; the controller is deterministic, so (terrain, controller, seed) fixes the result.

    on_step(env, reward, info, ended) runs after reset (reward 0) and after every step: `hexpipe play` streams
    and paces the episode with it.
    """
    from hexpipe.evaluation.video import Mp4Writer, caption
    from hexpipe.recording.episode import EpisodeLog, episode_metadata

    if job.controller.policy_dir is not None:
        import torch

        torch.set_num_threads(1)  # one core per worker
    start = time.perf_counter()
    if job.controller.gait is not None:  # the floors bound what a policy may choose, not a gait it is compared with
        params = params.model_copy(update={"cpg": params.cpg.holding(job.controller.gait)})
    if job.controller.lift_reflex:  # the hand-made adaptive baseline: the reflex, not the controller, lifts the legs
        params = params.model_copy(update={"task": params.task.model_copy(update={"lift_reflex": True})})
    controller = build(job.controller, params)
    env = HexapodEnv.from_params(
        params, job.scenario.recipe, obs_sensors=controller.sensors, initial_cpg=controller.initial_cpg,
        render_mode="rgb_array" if job.video else None,
    )
    try:
        obs, info = env.reset(seed=job.seed)
        with ExitStack() as stack:
            log = video = None
            if job.mcap is not None:
                job.mcap.parent.mkdir(parents=True, exist_ok=True)
                meta = episode_metadata(env, job.seed, params.model_dump_json(), index=job.index,
                                        controller=job.controller.name, policy_dir=job.controller.policy_dir or "")
                log = stack.enter_context(EpisodeLog(env, job.mcap, meta, log_every=params.collect.log_every))
                log.step(0.0, force=True)
            if job.video is not None:
                video = stack.enter_context(Mp4Writer(job.video, fps=params.sim.control_hz))
                video.add(env.render(), caption(env.terrain.name, info["time"], info["cpg"]))
            if on_step is not None:
                on_step(env, 0.0, info, False)
            trace = [_trace_row(info)]
            feet = [_feet(env)] if job.index == 0 else None
            while True:
                obs, reward, terminated, truncated, info = env.step(controller.act(obs))
                ended = terminated or truncated
                trace.append(_trace_row(info))
                if feet is not None:
                    feet.append(_feet(env))
                if log is not None:
                    log.step(reward, force=ended)
                if video is not None:
                    video.add(env.render(), caption(env.terrain.name, info["time"], info["cpg"]))
                if on_step is not None:
                    on_step(env, float(reward), info, ended)
                if ended:
                    break
        obstacles = _obstacles(env)
        stall_legs = _stall_legs(env, info["termination"])
        mass = env.robot_spec.total_mass
    finally:
        env.close()

    cpg = np.asarray(trace, dtype=np.float32)
    b_before, b_open = lift_before_and_away(cpg, obstacles)
    gait = job.controller.gait
    row = {
        "terrain": job.scenario.stem, "controller": job.controller.name, "episode": job.index, "seed": job.seed,
        "gait": gait_label(gait) if gait is not None else "",
        "success": bool(info["success"]), "termination": info["termination"] or "time_limit",
        "distance": float(info["distance"]), "time": float(info["time"]), "steps": len(trace) - 1,
        **{f"{k}_mean": float(cpg[:, i].mean()) for i, k in enumerate(TRACE_COLUMNS) if i >= 2},
        **{f"{k}_max": float(cpg[:, i].max()) for i, k in enumerate(TRACE_COLUMNS) if i >= 2},
        "b_before_block": b_before, "b_open": b_open,
        "stall_legs": stall_legs,  # stuck or fallen: the legs with a foot at a block face (see legs_at_faces)
        "energy_j": float(info["energy"]),
        "cost_of_transport": cost_of_transport(float(info["energy"]), mass, float(info["distance"])),
        "wall_s": time.perf_counter() - start,
    }
    return EpisodeResult(job, row, cpg, obstacles, None if feet is None else np.array(feet))
