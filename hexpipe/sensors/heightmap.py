"""The height map: terrain heights on a body-centred grid ahead of the robot, relative to a reference height.

It samples the terrain's own geometry (`Terrain.height_at`), which is exact for boxes and heightfields and orders of
magnitude cheaper than casting a ray per cell. Values are terrain heights relative to a reference height
(`sensors.heightmap_reference`): the robot's nominal stance plane (base height minus `body_height`, the default), or
the terrain under the base. Standing on flat ground, both read it about 0 and a 0.10 m block ahead +0.10. They
differ when the legs hold the body above or below its nominal height (the stance plane then moves every cell by as
much) and when the base is over a block (from the ground under it, the block reads 0 and the ground around -0.10).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from hexpipe.sensors.base import ImagePrep, Message, Sensor, SimView

if TYPE_CHECKING:
    from hexpipe.config import SensorConfig

HEADING_FRAME = "heading"  # base position at the map's reference height, yaw only (the env logs it to /tf)
LIMIT_M = 5.0  # observation bound (m)
# Heights are in metres relative to the stance plane. This window covers a dip of 15 cm and a raised block of up to
# 25 cm (the tallest the hexapod is asked to climb is well below that); flat ground maps to 0.375.
VAE_RANGE_M: tuple[float, float] = (-0.15, 0.25)


class HeightSource(Protocol):
    def height_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray: ...


def quat_to_yaw(q: np.ndarray) -> float:
    x, y, z, w = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def reference_height(terrain: HeightSource, base_pos: np.ndarray, body_height: float, reference: str) -> float:
    """The height (m, world) the map's cells are measured from: the stance plane (base z - body_height) or the
    terrain under the base (reference "ground")."""
    if reference == "ground":
        return float(terrain.height_at(np.asarray(base_pos[:1]), np.asarray(base_pos[1:2]))[0])
    return float(base_pos[2] - body_height)


class HeightMapSensor:
    """A rows x cols grid in the heading frame (yaw only), rows running forward, columns right-to-left."""

    def __init__(self, cfg: SensorConfig):
        self.reference = cfg.heightmap_reference
        near, far = cfg.heightmap_ahead
        half = cfg.heightmap_width / 2
        self.cell_x = (far - near) / cfg.heightmap_rows
        self.cell_y = cfg.heightmap_width / cfg.heightmap_cols
        fx = near + self.cell_x * (np.arange(cfg.heightmap_rows) + 0.5)
        fy = -half + self.cell_y * (np.arange(cfg.heightmap_cols) + 0.5)
        gx, gy = np.meshgrid(fx, fy, indexing="ij")
        self._local = np.stack([gx.ravel(), gy.ravel()])  # (2, rows*cols) in the heading frame (m)
        self.shape = (cfg.heightmap_rows, cfg.heightmap_cols)
        self.size = cfg.heightmap_rows * cfg.heightmap_cols
        self.origin = (near, -half)  # heading-frame position of the grid's corner (m)

    def read(self, terrain: HeightSource, base_xy: np.ndarray, yaw: float, plane_z: float) -> np.ndarray:
        """Terrain height (m, float32) above `plane_z` at every cell, for a robot at base_xy heading `yaw`."""
        c, s = math.cos(yaw), math.sin(yaw)
        lx, ly = self._local
        wx = base_xy[0] + c * lx - s * ly
        wy = base_xy[1] + s * lx + c * ly
        return (terrain.height_at(wx, wy) - plane_z).reshape(self.shape).astype(np.float32)

    def __call__(self, view: SimView) -> np.ndarray:
        plane = reference_height(view.terrain, view.base_pos, view.body_height, self.reference)
        grid = self.read(view.terrain, view.base_pos[:2], quat_to_yaw(view.base_quat), plane)
        return np.clip(grid, -LIMIT_M, LIMIT_M)


class HeightMap(Sensor):
    name = "heightmap"
    topic = "/heightmap"
    kind = "grid"
    image = ImagePrep(channels=1, low=VAE_RANGE_M[0], high=VAE_RANGE_M[1], units="m", channels_last=False,
                      nonfinite_to_low=True)
    config_keys = ("heightmap_rows", "heightmap_cols", "heightmap_ahead", "heightmap_width", "heightmap_reference")

    def frame_shape(self, cfg: SensorConfig) -> tuple[int, ...]:
        return (cfg.heightmap_rows, cfg.heightmap_cols)

    def space(self, cfg: SensorConfig):
        from gymnasium import spaces

        return spaces.Box(-LIMIT_M, LIMIT_M, shape=(cfg.heightmap_rows * cfg.heightmap_cols,), dtype=np.float32)

    def reader(self, cfg: SensorConfig) -> HeightMapSensor:
        return HeightMapSensor(cfg)

    def observation(self, reading: np.ndarray) -> np.ndarray:
        return reading.reshape(-1)  # row-major rows * cols: SB3 takes 1-D vectors or images

    def message(self, reading: np.ndarray, cfg: SensorConfig) -> Message:
        near, _ = cfg.heightmap_ahead
        cell = ((cfg.heightmap_ahead[1] - near) / cfg.heightmap_rows, cfg.heightmap_width / cfg.heightmap_cols)
        pose = (np.array([near, -cfg.heightmap_width / 2, 0.0]), np.array([0.0, 0.0, 0.0, 1.0]), cell)
        return Message(self.topic, self.kind, (reading, pose), frame_id=HEADING_FRAME)

    def decode(self, payload: Any) -> np.ndarray:
        return payload
