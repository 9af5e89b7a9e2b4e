"""A stride reflex read from the height map: a long stride, shortened only while two blocks lie within the feet's
reach.

Why (issue 10): held at the fixed gait's stride (a 0.4), the learned lift beats the fixed gait on most block courses
but crosses extra blocks 0.77-0.83 of the time (the `pinned` and `track` sweeps): eight of ten failures stop with the
front feet at the second block's face while the hind feet climb the first, the straddle. Fixed gaits at a 0.35 and
b 0.45-0.5 cross that course 20 of 20 times, at a 0.4 and b 0.45 only 9 of 20
(reports/experiments/straddle/fixed_strides.txt). A stride shortened everywhere near relief costs the time that the
long stride wins at single faces, so this reflex asks for the short stride only where the map shows two separate
raised regions in the zone (task.lift_free_zone, the feet's reach), and for the long one everywhere else.

Two uses. As a teacher (task.stride_teacher, the `straddle` sweep) the reward charges a's distance from the
reflex's stride and no leg is moved: the policies kept the long stride at the straddle. Steered to the reflex's
stride at run time, the same policies crossed extra blocks 50 of 50 (reports/experiments/straddle/stride_hold.txt),
so as a leg mover (task.stride_reflex, the stride at a straddle) the reflex caps every leg's stride at its own
while the policy's a is untouched, as the lift reflex raises the swing. Its stride moves no faster than a itself
may (cpg.rate_limit, cpg.fall_rate_limit).

Pure NumPy, a `hexpipe.sim.zone_reflex.ZoneReflex` with this module's trigger.
"""

from __future__ import annotations

import numpy as np

from hexpipe.sim.zone_reflex import ZoneReflex

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


def stride_reflex(mask: np.ndarray, short: float, long: float, rise: float, fall: float) -> ZoneReflex:
    """The stride (rad): toward `short` while the zone (`mask`) holds two raised regions or more (a straddle),
    toward `long` elsewhere (the env passes task.stride_reflex, or cpg.lower's a for the teacher alone, and
    cpg.upper's a); rise, fall: a's rate bounds (rad/s)."""
    return ZoneReflex("stride", mask, lambda heights, zone: raised_regions(heights, zone) >= 2, long, short, rise,
                      fall)
