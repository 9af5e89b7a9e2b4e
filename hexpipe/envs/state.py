"""What the env shows the outside world at one instant, as plain frozen data: the recorder (MCAP files and the live
Foxglove stream) maps these fields to topics, so it needs neither the env's internals nor the simulator.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

WORLD_FRAME = "world"
Transform = tuple[str, str, np.ndarray, np.ndarray]  # parent, child, translation xyz (m), quaternion xyzw


@dataclass(frozen=True, slots=True)
class EnvScene:
    """What stays fixed over an episode: the realised terrain and the robot's geometry."""

    terrain: str  # the realised terrain's name
    terrain_dict: dict[str, Any]  # `Terrain.to_dict()`, JSON-ready
    boxes: Sequence[Any]  # writer.BoxLike
    heightfields: Sequence[Any]  # writer.HeightfieldLike
    robot_shapes: Sequence[Any]  # sim.robot.LinkShape: .link, .kind, .position, .size, .rgba


@dataclass(frozen=True, slots=True)
class EnvState:
    """The env after its last reset or step (`HexapodEnv.state`)."""

    step: int  # control steps since reset
    time: float  # s of sim time
    terrain: str
    # world -> base_link and every link, world -> heading (base on the stance plane, yaw only), sensor frames
    transforms: tuple[Transform, ...]
    joint_names: tuple[str, ...]
    joint_position: np.ndarray  # rad
    joint_velocity: np.ndarray  # rad/s
    joint_effort: np.ndarray  # N m
    cpg_params: np.ndarray  # a, b (rad), omega (rad/s)
    cpg_rates: np.ndarray  # their first derivatives
    cpg_xy: np.ndarray  # (legs, 2) oscillator states
    reward_terms: Mapping[str, float]  # the last step's terms (zeros after reset)
    power: float  # W, mean mechanical joint power over the last control step
    energy: float  # J since reset
    distance: float  # m forward since reset
    termination: str | None
    labels: Mapping[str, float]  # `HexapodEnv.terrain_labels()`: obstacle and rise ahead (m)
    readings: Mapping[str, np.ndarray] = field(default_factory=dict)  # sensor name -> reading
