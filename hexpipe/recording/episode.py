"""Logging a `HexapodEnv` episode to MCAP: terrain and robot once, then the kept control steps.

Frames: world -> base_link and every link (so Foxglove's 3D panel animates the robot), world -> heading (the
height map's frame: base position on the stance plane, yaw only), base_link -> camera.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from hexpipe import __version__
from hexpipe.envs.hexapod import HexapodEnv, quat_to_yaw
from hexpipe.recording.writer import CAMERA_FRAME, HEADING_FRAME, WORLD_FRAME, EpisodeWriter
from hexpipe.sim.robot import robot_shapes

SENSORS = ("rgb", "heightmap")


def _yaw_quaternion(yaw: float) -> np.ndarray:
    return np.array([0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)])


def _pitch_quaternion(pitch: float) -> np.ndarray:
    return np.array([0.0, math.sin(pitch / 2), 0.0, math.cos(pitch / 2)])


class EpisodeLog:
    """Writes one episode of `env` to `path`; call `step` after reset and after every env.step."""

    def __init__(self, env: HexapodEnv, path: Path | None, metadata: dict[str, dict[str, str]], log_every: int = 1,
                 sensors: tuple[str, ...] = SENSORS, writer: EpisodeWriter | None = None, time_offset_ns: int = 0):
        """Logs to a new file at `path`, or (path None) into `writer`, which it leaves open: a live stream of
        several episodes keeps its channels. time_offset_ns shifts every stamp, so that stream's time increases."""
        if (path is None) == (writer is None):
            raise ValueError("EpisodeLog needs a path or an open writer, not both")
        self.env = env
        self.log_every = log_every
        self.sensors = sensors
        self.frames = 0
        self.time_offset_ns = time_offset_ns
        self._owns_writer = writer is None
        self.writer = EpisodeWriter(path, metadata) if writer is None else writer
        self._names = ["base_link", *env.robot_spec.link_names]
        cfg = env.sensor_cfg
        self._camera_tf = (
            np.asarray(cfg.camera_mount, dtype=float), _pitch_quaternion(math.radians(cfg.camera_pitch_deg))
        )
        self._grid_pose = (
            np.array([*env.heightmap.origin, 0.0]), np.array([0.0, 0.0, 0.0, 1.0]),
            (env.heightmap.cell_x, env.heightmap.cell_y),
        )
        self.log_static(time_offset_ns)

    def log_static(self, t_ns: int) -> None:
        """The terrain and the robot's geometry (logged once per file; a live stream repeats them for late viewers)."""
        self.writer.log_scene(t_ns, self.env.terrain.boxes, self.env.terrain.heightfields)
        self.writer.log_robot(t_ns, robot_shapes(self.env.robot_spec))

    def now_ns(self) -> int:
        """The stamp of the env's current step (ns): sim time, shifted by time_offset_ns."""
        return self.time_offset_ns + 1 + round(self.env.steps * self.env.control_dt * 1e9)

    def __enter__(self) -> EpisodeLog:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if self._owns_writer:
            self.writer.__exit__(exc_type, exc, tb)

    def step(self, reward: float, info: dict[str, Any], force: bool = False) -> bool:
        """Log the env's current state if this is a kept step (every `log_every`-th, or `force`)."""
        env = self.env
        if not force and env.steps % self.log_every:
            return False
        t_ns = self.now_ns()
        poses = env.robot.link_poses()
        base_pos, base_quat = poses[0]
        transforms = [(WORLD_FRAME, name, pos, quat) for name, (pos, quat) in zip(self._names, poses, strict=True)]
        yaw = quat_to_yaw(base_quat)
        plane = np.array([base_pos[0], base_pos[1], base_pos[2] - env.sim_cfg.body_height])
        transforms.append((WORLD_FRAME, HEADING_FRAME, plane, _yaw_quaternion(yaw)))
        transforms.append(("base_link", CAMERA_FRAME, *self._camera_tf))
        sensed = env.sense(self.sensors, base=(base_pos, base_quat))
        q, dq, tau = env.robot.joint_states()
        xy = env.cpg.xy
        a, b, omega = env.cpg.params
        da, db, domega = env.cpg.rates
        self.writer.log_step(
            t_ns,
            transforms=transforms,
            rgb=sensed.get("rgb"),
            heightmap=sensed.get("heightmap"),
            heightmap_pose=self._grid_pose if "heightmap" in sensed else None,
            joints={"name": env.robot_spec.joint_names, "position": q.tolist(), "velocity": dq.tolist(),
                    "effort": tau.tolist()},
            cpg={"a": a, "b": b, "omega": omega, "a_rate": da, "b_rate": db, "omega_rate": domega,
                 "x": xy[:, 0].tolist(), "y": xy[:, 1].tolist()},
            step={"step": env.steps, "time": env.steps * env.control_dt, "reward": float(reward),
                  "power": float(info.get("power", 0.0)), "energy": float(info.get("energy", 0.0)),
                  "distance": float(info.get("distance", 0.0)), **env.terrain_labels(),  # null: nothing ahead
                  "termination": info.get("termination") or "", "terrain": env.terrain.name},
        )
        self.frames += 1
        return True

    def close(self) -> None:
        if self._owns_writer:
            self.writer.close()


def episode_metadata(env: HexapodEnv, seed: int, params_json: str, **episode: Any) -> dict[str, dict[str, str]]:
    """MCAP metadata records: the episode, the realised terrain, the params and the hexpipe version."""
    return {
        "episode": {"seed": str(seed), "terrain": env.terrain.name, "hexpipe_version": __version__,
                    **{k: str(v) for k, v in episode.items()}},
        "terrain": {"json": json.dumps(env.terrain.to_dict())},
        "params": {"json": params_json},
    }
