"""A heading reflex: the legs on the side the robot has turned towards take shorter strides and the others longer
ones, so the body turns back to the course's direction (+x, the start's heading).

Why (issue 10): with the elevator, the policies' last failures past a block are not a crawl but a turn. A bump at a
face swings the base by 0.3-0.5 rad, and from past about half a radian the gait turns further by itself, towards
walking sideways. Four of the eight `elev150` losses in 1350 suite episodes, and both losses of the fixed gaits with
the elevator, end about 90 degrees off course with their progress along x stalled (reports/experiments/README.md,
"heading: the last failures past a block are a turn, not a crawl"). The paper's CPG has no steering; a hexapod
steers by the difference in stride length between its two sides, as a tracked vehicle does. Pure NumPy; the env
passes the base's yaw.
"""

from __future__ import annotations

import numpy as np

MAX_CHANGE = 0.3  # at most +-30% of the commanded stride on either side, so a turn never stops a side's legs


def stride_scales(yaw: float, side: np.ndarray, gain: float, max_change: float = MAX_CHANGE) -> np.ndarray:
    """(legs,) factors on each leg's fore/aft swing (the oscillator's x) for a base yaw (rad, CCW positive, 0 along
    the course). `side`: +1 for a left leg, -1 for a right one. Turned right (yaw < 0), the left legs shorten their
    strides and the right legs lengthen them by gain * |yaw| each, clipped to `max_change`, which turns the body left.
    """
    change = np.clip(gain * float(np.arctan2(np.sin(yaw), np.cos(yaw))), -max_change, max_change)
    return 1.0 + change * np.asarray(side, dtype=float)
