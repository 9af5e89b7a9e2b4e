"""A stride reflex read from the height map: a long stride, shortened only while two blocks lie within the feet's
reach.

Why (issue 10): held at the fixed gait's stride (a 0.4), the learned lift beats the fixed gait on most block courses
but crosses extra blocks 0.77-0.83 of the time (the `pinned` and `track` sweeps): eight of ten failures stop with the
front feet at the second block's face while the hind feet climb the first, the straddle. Fixed gaits at a 0.35 and
b 0.45-0.5 cross that course 20 of 20 times, at a 0.4 and b 0.45 only 9 of 20
(reports/experiments/straddle/fixed_strides.txt). A stride shortened everywhere near relief costs the time that the
long stride wins at single faces, so this reflex asks for the short stride only where the map shows two separate
raised regions in the zone (task.lift_free_zone, the feet's reach), and for the long one everywhere else.

It only teaches (task.stride_teacher): the reward charges a's distance from the reflex's stride; no leg is moved.
The target moves no faster than a itself may (cpg.rate_limit, cpg.fall_rate_limit), so the policy can follow it.

Pure NumPy: the env hands it each control step's height map and asks for the stride once per control step.
"""

from __future__ import annotations

import numpy as np

from hexpipe.sim.lift_reflex import ramp_toward

RISE_M = 0.05  # m above the zone's lowest row that counts as raised: half the paper's 0.10 m block, above most of
# rough ground's bumps (0-0.07 m), so a low bump pair rarely reads as two blocks


def raised_regions(heightmap: np.ndarray, mask: np.ndarray, rise: float = RISE_M) -> int:
    """How many separate raised regions the zone (`mask`'s cells) holds along the heading: the zone's profile (the
    highest cell of each map row, rows running along the heading) is raised where it stands more than `rise` m above
    its lowest row, and each unbroken run of raised rows is one region."""
    heights = np.asarray(heightmap, dtype=float).reshape(mask.shape)
    rows = mask.any(axis=1)
    profile = np.where(mask, heights, -np.inf).max(axis=1)[rows]
    raised = profile > profile.min() + rise
    return int(raised[0]) + int(np.count_nonzero(raised[1:] & ~raised[:-1]))


class StrideReflex:
    """The reflex's stride a (rad) over an episode: `see` each height map, `advance` once per control step."""

    def __init__(self, mask: np.ndarray, short: float, long: float, rise: float, fall: float):
        """mask: the zone's cells (`hexpipe.sim.lift_reflex.zone_mask`); short, long: the stride at a straddle and
        elsewhere (rad; the env passes a's bounds, cpg.lower and cpg.upper); rise, fall: a's rate bounds (rad/s)."""
        if not mask.any():
            raise ValueError("the stride reflex's zone holds no height-map cell")
        self.mask, self.short, self.long, self.rise, self.fall = mask, short, long, rise, fall
        self.level, self.straddle = long, False

    def reset(self) -> None:
        self.level, self.straddle = self.long, False

    def see(self, heightmap: np.ndarray) -> None:
        """Read the zone of this height map (rows x cols, m): a straddle when it holds two raised regions or more."""
        self.straddle = raised_regions(heightmap, self.mask) >= 2

    def advance(self, dt: float) -> float:
        """The stride (rad) for the next `dt` s: ramped toward `short` while the last map showed a straddle, else
        toward `long`."""
        target = self.short if self.straddle else self.long
        self.level = ramp_toward(self.level, target, self.rise, self.fall, dt)
        return self.level
