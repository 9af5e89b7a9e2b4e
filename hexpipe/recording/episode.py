"""Logging an env's episode to MCAP: terrain and robot once, then the kept control steps.

The env hands over plain snapshots (`EnvScene` once, `EnvState` per kept step; hexpipe/envs/state.py) and this
module maps them to topics, so it reads no simulator state itself. Frames: world -> base_link and every link (so
Foxglove's 3D panel animates the robot), world -> heading (the height map's frame: base position on the stance
plane, yaw only), and each sensor's own frames (base_link -> camera). Every registered sensor is logged on its own
topic (`hexpipe.sensors`), whatever the observation holds.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any, Protocol

from hexpipe import __version__
from hexpipe import sensors as registry
from hexpipe.envs.state import EnvScene, EnvState
from hexpipe.recording.writer import EpisodeWriter


class Recordable(Protocol):
    """What the recorder needs of an env (`HexapodEnv`)."""

    sensor_cfg: Any  # hexpipe.config.SensorConfig: how the sensors' readings are laid out
    steps: int
    control_dt: float

    def scene(self) -> EnvScene: ...
    def state(self, sensors: Iterable[str] = ()) -> EnvState: ...


class EpisodeLog:
    """Writes one episode of `env` to `path`; call `step` after reset and after every env.step."""

    def __init__(self, env: Recordable, path: Path | None, metadata: dict[str, dict[str, str]], log_every: int = 1,
                 sensors: tuple[str, ...] | None = None, writer: EpisodeWriter | None = None,
                 time_offset_ns: int = 0):
        """Logs to a new file at `path`, or (path None) into `writer`, which it leaves open: a live stream of
        several episodes keeps its channels. time_offset_ns shifts every stamp, so that stream's time increases.
        sensors: those to log (default: every registered sensor)."""
        if (path is None) == (writer is None):
            raise ValueError("EpisodeLog needs a path or an open writer, not both")
        self.env = env
        self.log_every = log_every
        self.sensors = registry.names() if sensors is None else tuple(sensors)
        self.frames = 0
        self.time_offset_ns = time_offset_ns
        self._owns_writer = writer is None
        self.writer = EpisodeWriter(path, metadata) if writer is None else writer
        self.log_static(time_offset_ns)

    def log_static(self, t_ns: int) -> None:
        """The terrain and the robot's geometry (logged once per file; a live stream repeats them for late viewers)."""
        scene = self.env.scene()
        self.writer.log_scene(t_ns, scene.boxes, scene.heightfields)
        self.writer.log_robot(t_ns, scene.robot_shapes)

    def now_ns(self) -> int:
        """The stamp of the env's current step (ns): sim time, shifted by time_offset_ns."""
        return self.time_offset_ns + 1 + round(self.env.steps * self.env.control_dt * 1e9)

    def __enter__(self) -> EpisodeLog:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if self._owns_writer:
            self.writer.__exit__(exc_type, exc, tb)

    def step(self, reward: float, force: bool = False) -> bool:
        """Log the env's current state (`env.state()`) if this is a kept step (every `log_every`-th, or `force`);
        reward: the last step's total (0 after reset)."""
        if not force and self.env.steps % self.log_every:
            return False
        state = self.env.state(self.sensors)
        cfg = self.env.sensor_cfg
        a, b, omega = state.cpg_params.tolist()
        da, db, domega = state.cpg_rates.tolist()
        self.writer.log_step(
            self.now_ns(),
            transforms=state.transforms,
            sensors=[registry.get(name).message(reading, cfg) for name, reading in state.readings.items()],
            joints={"name": list(state.joint_names), "position": state.joint_position.tolist(),
                    "velocity": state.joint_velocity.tolist(), "effort": state.joint_effort.tolist()},
            cpg={"a": a, "b": b, "omega": omega, "a_rate": da, "b_rate": db, "omega_rate": domega,
                 "x": state.cpg_xy[:, 0].tolist(), "y": state.cpg_xy[:, 1].tolist()},
            step={"step": state.step, "time": state.time, "reward": float(reward),
                  "power": state.power, "energy": state.energy,
                  "distance": state.distance, **state.labels,  # null: nothing ahead
                  "termination": state.termination or "", "terrain": state.terrain,
                  "reward_terms": {k: float(v) for k, v in state.reward_terms.items()}},
        )
        self.frames += 1
        return True

    def close(self) -> None:
        if self._owns_writer:
            self.writer.close()


def episode_metadata(env: Recordable, seed: int, params_json: str, **episode: Any) -> dict[str, dict[str, str]]:
    """MCAP metadata records: the episode, the realised terrain, the params and the hexpipe version."""
    scene = env.scene()
    return {
        "episode": {"seed": str(seed), "terrain": scene.terrain, "hexpipe_version": __version__,
                    **{k: str(v) for k, v in episode.items()}},
        "terrain": {"json": json.dumps(scene.terrain_dict)},
        "params": {"json": params_json},
    }
