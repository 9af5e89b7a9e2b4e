"""The sensor registry: every sensor the robot can carry, by name, each declaring in one module its observation
space, how it is read from the sim, its MCAP topic and message, and (image sensors) the VAE's preprocessing.

`task.sensors` picks the observed ones; the recorder logs all of them. Adding a sensor is one module here plus its
line in `SENSORS`.
"""

from __future__ import annotations

from hexpipe.sensors.base import ImagePrep, Message, Sensor, SimView, Transform
from hexpipe.sensors.camera import RgbCamera
from hexpipe.sensors.contacts import FootContacts
from hexpipe.sensors.heightmap import HeightMap

SENSORS: dict[str, Sensor] = {s.name: s for s in (RgbCamera(), HeightMap(), FootContacts())}

__all__ = ["SENSORS", "ImagePrep", "Message", "Sensor", "SimView", "Transform", "get", "image_sensors", "names"]


def names() -> tuple[str, ...]:
    """Every sensor's name, in logging order."""
    return tuple(SENSORS)


def image_sensors() -> tuple[str, ...]:
    """The sensors the VAE can encode."""
    return tuple(name for name, sensor in SENSORS.items() if sensor.image is not None)


def get(name: str) -> Sensor:
    """The sensor called `name`; ValueError (one line, listing the known ones) otherwise."""
    try:
        return SENSORS[name]
    except KeyError:
        raise ValueError(f"unknown sensor {name!r}; known: {', '.join(SENSORS)}") from None
