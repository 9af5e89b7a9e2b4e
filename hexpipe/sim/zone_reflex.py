"""A reflex read from the height map's zone around the feet: a level (rad) that ramps toward one value while the
zone shows what the reflex looks for and toward another elsewhere.

Two reflexes share it: the lift reflex (hexpipe/sim/lift_reflex.py: b's ceiling near uneven ground) and the stride
reflex (hexpipe/sim/stride_reflex.py: a short stride at the straddle of two blocks). Each is this class with its own
trigger. The level moves no faster than the CPG parameter it stands for may (cpg.rate_limit, cpg.fall_rate_limit),
so a step into the zone is a ramp, not a jump.

Pure NumPy: the env hands it each control step's height map and asks for the level once per control step.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

HALF_WIDTH = 0.3  # m to either side of the heading: the feet's lateral reach, as `Terrain.relief` samples it

Trigger = Callable[[np.ndarray, np.ndarray], bool]  # (heights (rows, cols) m, zone mask) -> does the reflex act
Strength = Callable[[np.ndarray, np.ndarray], float]  # (heights, zone mask) -> how far toward `active`, in [0, 1]


def zone_mask(
    near: float, far: float, rows: int, cols: int, width: float, behind: float, ahead: float,
    half_width: float = HALF_WIDTH,
) -> np.ndarray:
    """(rows, cols) bool: the height-map cells whose centres lie from `behind` m behind the base to `ahead` m ahead
    and within `half_width` m to either side. The map spans near..far m along the heading (rows) and `width` m
    across (cols), as `hexpipe.sensors.heightmap.HeightMapSensor` lays it out."""
    along = near + (far - near) / rows * (np.arange(rows) + 0.5)
    across = -width / 2 + width / cols * (np.arange(cols) + 0.5)
    return ((along >= -behind) & (along <= ahead))[:, None] & (np.abs(across) <= half_width)[None, :]


def ramp_toward(level: float, target: float, rise: float, fall: float, dt: float) -> float:
    """`level` moved toward `target` by at most rise * dt up or fall * dt down (rates in rad/s, dt in s)."""
    return min(level + rise * dt, target) if target >= level else max(level - fall * dt, target)


class ZoneReflex:
    """A level (rad) over an episode: `see` each height map, `advance` once per control step."""

    def __init__(self, name: str, mask: np.ndarray, trigger: Trigger, idle: float, active: float, rise: float,
                 fall: float, strength: Strength | None = None):
        """name: for errors ("lift", "stride"); mask: the zone's cells (`zone_mask`); trigger: whether a map's zone
        calls for `active`; idle, active: the level elsewhere and while triggered (rad; it starts at idle); rise,
        fall: the level's rate bounds (rad/s); strength: while triggered, the fraction of the way from idle to
        active the map's zone calls for (None: all of it)."""
        if not mask.any():
            raise ValueError(f"the {name} reflex's zone holds no height-map cell")
        self.mask, self.trigger, self.strength = mask, trigger, strength
        self.idle, self.active, self.rise, self.fall = idle, active, rise, fall
        self.level, self.triggered, self.fraction = idle, False, 1.0

    def reset(self) -> None:
        self.level, self.triggered, self.fraction = self.idle, False, 1.0

    def see(self, heightmap: np.ndarray) -> None:
        """Read the zone of this height map (rows x cols, m)."""
        heights = np.asarray(heightmap, dtype=float).reshape(self.mask.shape)
        self.triggered = bool(self.trigger(heights, self.mask))
        if self.triggered and self.strength is not None:
            self.fraction = min(1.0, max(0.0, float(self.strength(heights, self.mask))))

    def advance(self, dt: float) -> float:
        """The level (rad) for the next `dt` s: ramped toward `active` (or the strength's fraction of the way there)
        while the last map triggered the reflex, else toward `idle`."""
        target = self.idle + (self.active - self.idle) * self.fraction if self.triggered else self.idle
        self.level = ramp_toward(self.level, target, self.rise, self.fall, dt)
        return self.level
