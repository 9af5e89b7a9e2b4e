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

The zone is task.lift_zone: task.lift_reflex_zone when set (e.g. [0.2, 0.7], which lets the lift down once the body
has passed a block), else lift_free_zone.

Pure NumPy, a `hexpipe.sim.zone_reflex.ZoneReflex` with this module's trigger.
"""

from __future__ import annotations

import numpy as np

from hexpipe.sim.zone_reflex import ZoneReflex


def map_relief(heightmap: np.ndarray, mask: np.ndarray) -> float:
    """How far (m) the mapped terrain rises and falls, max minus min, over the cells in `mask`: the height map's
    reading of `Terrain.relief`. Independent of the map's reference height."""
    cells = np.asarray(heightmap, dtype=float).reshape(mask.shape)[mask]
    return float(cells.max() - cells.min())


def lift_reflex(mask: np.ndarray, relief: float, floor: float, ceiling: float, rise: float, fall: float,
                full_relief: float | None = None) -> ZoneReflex:
    """The lift (rad): toward `ceiling` while the zone (`mask`) rises or falls by more than `relief` m (the env
    passes the lift price's waiver, `hexpipe.envs.rewards.RELIEF_M`), toward `floor` elsewhere; floor, ceiling: b's
    bounds; rise, fall: b's rate bounds (rad/s). With `full_relief` (m), a relief under it asks only that fraction
    of the way from floor to ceiling: a 6 cm step less lift than a 10 cm block (task.lift_reflex_relief)."""
    strength = None if full_relief is None else (lambda heights, zone: map_relief(heights, zone) / full_relief)
    return ZoneReflex("lift", mask, lambda heights, zone: map_relief(heights, zone) > relief, floor, ceiling, rise,
                      fall, strength)
