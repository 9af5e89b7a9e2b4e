"""Terrain sensors: a body-centred height map ahead of the robot and an RGB camera on the body.

The height map samples the terrain's own geometry (`Terrain.height_at`), which is exact for boxes and
heightfields and orders of magnitude cheaper than casting a ray per cell. Values are terrain heights relative to
the robot's nominal stance plane (base height minus `body_height`): flat ground reads about 0, a 0.10 m block +0.10.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from hexpipe.config import SensorConfig


class HeightSource(Protocol):
    def height_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray: ...


class HeightMapSensor:
    """A rows x cols grid in the heading frame (yaw only), rows running forward, columns right-to-left."""

    def __init__(self, cfg: SensorConfig):
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


def _rotate(quat_xyzw: np.ndarray, v: np.ndarray) -> np.ndarray:
    x, y, z, w = quat_xyzw
    q = np.array([x, y, z])
    t = 2.0 * np.cross(q, v)
    return v + w * t + np.cross(q, t)


class Camera:
    """An RGB camera fixed to the base, looking ahead and `camera_pitch_deg` down (PyBullet TinyRenderer)."""

    def __init__(self, cfg: SensorConfig, client: int):
        import pybullet as p

        self._p = p
        self.client = client
        self.width, self.height = cfg.camera_width, cfg.camera_height
        self.mount = np.asarray(cfg.camera_mount, dtype=float)
        pitch = math.radians(cfg.camera_pitch_deg)
        self.forward = np.array([math.cos(pitch), 0.0, -math.sin(pitch)])
        self.up = np.array([math.sin(pitch), 0.0, math.cos(pitch)])
        self.projection = p.computeProjectionMatrixFOV(
            fov=cfg.camera_fov_deg, aspect=self.width / self.height, nearVal=0.03, farVal=6.0
        )

    def read(self, base_pos: np.ndarray, base_quat: np.ndarray) -> np.ndarray:
        """An H x W x 3 uint8 image from the body camera."""
        eye = base_pos + _rotate(base_quat, self.mount)
        target = eye + _rotate(base_quat, self.forward)
        view = self._p.computeViewMatrix(eye.tolist(), target.tolist(), _rotate(base_quat, self.up).tolist())
        _, _, rgba, _, _ = self._p.getCameraImage(
            self.width, self.height, view, self.projection, renderer=self._p.ER_TINY_RENDERER,
            flags=self._p.ER_NO_SEGMENTATION_MASK, shadow=0, physicsClientId=self.client,
        )
        return np.asarray(rgba, dtype=np.uint8).reshape(self.height, self.width, 4)[:, :, :3]
