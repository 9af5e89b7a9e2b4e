"""The body camera: an RGB image from a camera fixed to the base, looking ahead and down (PyBullet TinyRenderer)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from hexpipe.sensors.base import ImagePrep, Message, Sensor, SimView, Transform

if TYPE_CHECKING:
    from hexpipe.config import SensorConfig

CAMERA_FRAME = "camera"


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


class _LazyCamera:
    """Made on first use, bound to the client it is first read in (only rgb observations or loggers need it)."""

    def __init__(self, cfg: SensorConfig):
        self.cfg = cfg
        self.camera: Camera | None = None

    def __call__(self, view: SimView) -> np.ndarray:
        if self.camera is None or self.camera.client != view.client:
            self.camera = Camera(self.cfg, view.client)
        return self.camera.read(view.base_pos, view.base_quat)


class RgbCamera(Sensor):
    name = "rgb"
    topic = "/camera/image"
    kind = "image"
    image = ImagePrep(channels=3, low=0.0, high=255.0, units="uint8 intensity", channels_last=True, dtype="uint8",
                      store_uint8=True)
    config_keys = ("camera_width", "camera_height", "camera_fov_deg", "camera_pitch_deg", "camera_mount")

    def frame_shape(self, cfg: SensorConfig) -> tuple[int, ...]:
        return (cfg.camera_height, cfg.camera_width, 3)

    def space(self, cfg: SensorConfig):
        from gymnasium import spaces

        return spaces.Box(0, 255, shape=self.frame_shape(cfg), dtype=np.uint8)

    def reader(self, cfg: SensorConfig) -> _LazyCamera:
        return _LazyCamera(cfg)

    def message(self, reading: np.ndarray, cfg: SensorConfig) -> Message:
        return Message(self.topic, self.kind, reading, frame_id=CAMERA_FRAME)

    def decode(self, payload: Any) -> np.ndarray:
        return payload

    def frames(self, cfg: SensorConfig) -> list[Transform]:
        pitch = math.radians(cfg.camera_pitch_deg)
        quat = np.array([0.0, math.sin(pitch / 2), 0.0, math.cos(pitch / 2)])
        return [("base_link", CAMERA_FRAME, np.asarray(cfg.camera_mount, dtype=float), quat)]
