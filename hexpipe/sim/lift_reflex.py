"""A lift reflex read from the height map: the legs swing high wherever the map shows uneven ground in the feet's reach.

Why (issue 10): every trained policy so far lets b fall at extra blocks' straddle, the front feet at the second face
while the hind feet climb the first. At run time, b driven to its ceiling wherever the true terrain in the feet's
reach (task.lift_free_zone, 0.6 m behind the base to 0.7 m ahead) rises or falls by more than 3 cm took four untrained
policies from 32 to 39 of 40 extra-block crossings (reports/experiments/ceiling/hold_lift.py --zone). Here the same
rule reads the robot's own height map, so it is perception, not the simulator's terrain.

The policy keeps b: the reflex only raises the swing lift (a floor under every leg's lift, as `cpg.lift_follows`'
trail is), so a policy can walk low on open ground and leave the faces to the reflex, or lift earlier itself. The
reflex's lift moves toward its target (b's ceiling near uneven ground, b's floor elsewhere) no faster than b itself
may (cpg.rate_limit, cpg.fall_rate_limit), so a step into the zone is a ramp, not a jump.

Pure NumPy: the env hands it each control step's height map and asks for the lift once per control step.
"""

from __future__ import annotations

import numpy as np

HALF_WIDTH = 0.3  # m to either side of the heading: the feet's lateral reach, as `Terrain.relief` samples it


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


def map_relief(heightmap: np.ndarray, mask: np.ndarray) -> float:
    """How far (m) the mapped terrain rises and falls, max minus min, over the cells in `mask`: the height map's
    reading of `Terrain.relief`. Independent of the map's reference height."""
    cells = np.asarray(heightmap, dtype=float).reshape(mask.shape)[mask]
    return float(cells.max() - cells.min())


def ramp_toward(level: float, target: float, rise: float, fall: float, dt: float) -> float:
    """`level` moved toward `target` by at most rise * dt up or fall * dt down (rates in rad/s, dt in s)."""
    return min(level + rise * dt, target) if target >= level else max(level - fall * dt, target)


class LiftReflex:
    """The reflex's lift (rad) over an episode: `see` each height map, `advance` once per control step."""

    def __init__(self, mask: np.ndarray, relief: float, floor: float, ceiling: float, rise: float, fall: float):
        """mask: the zone's cells (`zone_mask`); relief: the rise or fall (m) above which the zone is uneven (the
        env passes the lift price's waiver, `hexpipe.envs.rewards.RELIEF_M`); floor, ceiling: b's bounds (rad);
        rise, fall: b's rate bounds (rad/s)."""
        if not mask.any():
            raise ValueError("the lift reflex's zone holds no height-map cell")
        self.mask, self.relief = mask, relief
        self.floor, self.ceiling, self.rise, self.fall = floor, ceiling, rise, fall
        self.level, self.uneven = floor, False

    def reset(self) -> None:
        self.level, self.uneven = self.floor, False

    def see(self, heightmap: np.ndarray) -> None:
        """Read the zone of this height map (rows x cols, m): uneven when it rises or falls by more than `relief`."""
        self.uneven = map_relief(heightmap, self.mask) > self.relief

    def advance(self, dt: float) -> float:
        """The lift (rad) for the next `dt` s: ramped toward the ceiling while the last map was uneven, else
        toward the floor."""
        target = self.ceiling if self.uneven else self.floor
        self.level = ramp_toward(self.level, target, self.rise, self.fall, dt)
        return self.level
