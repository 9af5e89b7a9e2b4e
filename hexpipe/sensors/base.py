"""What a sensor is: one object per kind that says how it is observed, read, logged and (for images) encoded.

A sensor is stateless and shared; `reader(cfg)` makes the per-env part (a camera bound to a PyBullet client, a
height map's precomputed grid), which `HexapodEnv` calls with a `SimView` of the moment. Nothing here imports
gymnasium, PyBullet or the recorder at import time: the registry is cheap to import from the recorder and the VAE.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Literal

import numpy as np

if TYPE_CHECKING:
    from gymnasium import spaces

    from hexpipe.config import SensorConfig

Transform = tuple[str, str, np.ndarray, np.ndarray]  # parent, child, translation xyz (m), quaternion xyzw
MessageKind = Literal["image", "grid", "json"]  # foxglove.RawImage (rgb8), foxglove.Grid (one float32 field), JSON


@dataclass(frozen=True, slots=True)
class SimView:
    """What a sensor may read at one instant: the PyBullet client, the robot and terrain as built, the base pose.

    robot: a `hexpipe.sim.robot.Robot` (body id, foot links); terrain: a `hexpipe.sim.terrain.Terrain`.
    """

    client: int
    robot: Any
    terrain: Any
    base_pos: np.ndarray  # m, world
    base_quat: np.ndarray  # xyzw
    body_height: float  # m; the nominal stance plane is base z - body_height


@dataclass(frozen=True, slots=True)
class Message:
    """A reading as one MCAP message: the writer encodes `payload` by `kind` on `topic`, in frame `frame_id`.

    image: H x W x 3 uint8. grid: (R x C float32 heights, (origin xyz, quaternion xyzw, (cell_x, cell_y))). json: a
    dict (its JSON schema, titled `schema`, is inferred from the first message).
    """

    topic: str
    kind: MessageKind
    payload: Any
    frame_id: str = ""
    schema: str = ""


@dataclass(frozen=True, slots=True)
class ImagePrep:
    """How the VAE takes a sensor's frames: value window to [0, 1], channels, dtype, storage.

    Values are mapped by clip((x - low) / (high - low), 0, 1); `nonfinite_to_low` reads NaN (no hit) as `low`.
    """

    channels: int
    low: float
    high: float
    units: str
    channels_last: bool  # frames are (H, W, channels); else (R, C) with one channel
    dtype: str | None = None  # the only accepted frame dtype (e.g. "uint8"), None for any float
    nonfinite_to_low: bool = False
    store_uint8: bool = False  # train-vae keeps preprocessed frames as uint8 (lossless for 8-bit sources)

    def describe(self) -> str:
        """The expected batch layout, for error messages."""
        dims = f"(N, H, W, {self.channels})" if self.channels_last else "(N, R, C)"
        return f"{dims} {self.dtype or 'float'}"


class Sensor(ABC):
    """One kind of sensor; subclasses set the class attributes and implement `space`, `reader` and `message`."""

    name: ClassVar[str]  # the key in task.sensors, the observation Dict and `HexapodEnv.sense`
    topic: ClassVar[str]  # its MCAP topic
    kind: ClassVar[MessageKind]  # how it is logged there (`Message`)
    image: ClassVar[ImagePrep | None] = None  # set when the VAE can encode it
    config_keys: ClassVar[tuple[str, ...]] = ()  # SensorConfig keys that change what its readings mean

    @abstractmethod
    def frame_shape(self, cfg: SensorConfig) -> tuple[int, ...]:
        """Shape of one reading (what `sense` returns and the recorder logs)."""

    @abstractmethod
    def space(self, cfg: SensorConfig) -> spaces.Box:
        """Its entry in the observation Dict."""

    @abstractmethod
    def reader(self, cfg: SensorConfig) -> Callable[[SimView], np.ndarray]:
        """A reader for one env: SimView -> reading of `frame_shape`."""

    @abstractmethod
    def message(self, reading: np.ndarray, cfg: SensorConfig) -> Message:
        """The reading as it is logged."""

    @abstractmethod
    def decode(self, payload: Any) -> np.ndarray:
        """A logged message, decoded by its kind (image or grid array, or JSON dict), back to the reading."""

    def observation(self, reading: np.ndarray) -> np.ndarray:
        """The reading as the observation holds it (SB3 wants 1-D vectors or images)."""
        return reading

    def frames(self, cfg: SensorConfig) -> list[Transform]:
        """Fixed frames the sensor hangs on base_link, logged to /tf every step."""
        return []
