"""Speed benchmarks: env steps per second for physics only, + height map, + camera, per terrain.

Configurations are interleaved window by window (A B C A B C ...) so that machine noise hits all of them alike,
and medians are reported. Sensor costs are also timed directly (one sensor read per control step), which is the
sharper number: an env step is mostly physics, and its noise is larger than a height map read.
"""

from __future__ import annotations

import os
import statistics
import time

import numpy as np

from hexpipe.config import Params
from hexpipe.envs.hexapod import HexapodEnv, quat_to_yaw

SENSOR_SETS = {"physics": (), "heightmap": ("heightmap",), "camera": ("rgb",)}


def _pin_one_core() -> None:
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})


def _window(env: HexapodEnv, steps: int) -> float:
    """Median-friendly: seconds per env step over `steps` steps (resetting on episode end)."""
    start = time.perf_counter()
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(np.zeros(3))
        if terminated or truncated:
            env.reset()
    return (time.perf_counter() - start) / steps


def bench_env(params: Params, terrains: tuple[str, ...], windows: int = 7, steps: int = 60) -> dict:
    """Env step rate (steps/s, one core) for each terrain and sensor set, plus direct sensor read costs."""
    _pin_one_core()
    results: dict = {"windows": windows, "steps_per_window": steps, "control_hz": params.sim.control_hz}
    for terrain in terrains:
        envs = {
            name: HexapodEnv(
                terrain, sim=params.sim, cpg=params.cpg, sensors=params.sensors,
                task=params.task.model_copy(update={"sensors": sensors}),
            )
            for name, sensors in SENSOR_SETS.items()
        }
        for env in envs.values():
            env.reset(seed=0)
            _window(env, 5)  # warm-up
        times: dict[str, list[float]] = {name: [] for name in envs}
        for _ in range(windows):
            for name, env in envs.items():
                times[name].append(_window(env, steps))
        row = {name: {"ms_per_step": 1e3 * statistics.median(t), "steps_per_s": 1 / statistics.median(t)}
               for name, t in times.items()}
        physics = statistics.median(times["physics"])
        for name in ("heightmap", "camera"):
            row[name]["overhead_vs_physics"] = statistics.median(times[name]) / physics - 1

        row["heightmap_read_ms"], row["camera_read_ms"] = _sensor_read_ms(envs)
        row["heightmap_read_vs_physics_step"] = row["heightmap_read_ms"] / row["physics"]["ms_per_step"]
        results[terrain] = row
        for env in envs.values():
            env.close()
    return results


def _sensor_read_ms(envs: dict[str, HexapodEnv]) -> tuple[float, float]:
    """Median cost (ms) of one height-map read and one camera frame at the robot's current pose."""
    hm_env, cam_env = envs["heightmap"], envs["camera"]
    pos, quat, _, _ = hm_env.robot.base_state()
    yaw = quat_to_yaw(quat)
    heightmap = _median_call(lambda: hm_env.heightmap.read(hm_env.terrain, pos[:2], yaw, 0.0))
    camera = _median_call(lambda: cam_env.camera.read(pos, quat), repeats=50)
    return 1e3 * heightmap, 1e3 * camera


def _median_call(fn, repeats: int = 300) -> float:
    fn()
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)
