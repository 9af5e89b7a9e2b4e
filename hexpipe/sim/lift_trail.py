"""Follow-the-leader lift: each leg lifts at least as high as the front legs did where it now stands.

The policy sets one lift b for all six legs. Over a block the front feet reach the face first, the middle feet
0.47 m and the hind feet 0.93 m later (the feet's spacing along x). A policy that lowers b once its front legs
are up leaves the hind feet at the face: where the default's failures and the `floors` sweep's stopped
(reports/experiments, "floors"). With `cpg.lift_follows`, each leg's lift is the larger of the commanded b and the
largest b commanded while the base stood where it put the front feet over this leg's foot now, so the
policy chooses the lift once per place and every leg carries it over. A fixed gait is unchanged (b never varies).

Pure NumPy: the env keeps the (base x, b) trail and asks for the six lift floors once per control step.
"""

from __future__ import annotations

import math

import numpy as np

from hexpipe.sim.robot import RobotSpec

WINDOW = 0.1  # m: a trailing foot takes the lifts commanded within this distance of its place (about half a stride)


def foot_lags(spec: RobotSpec, stance_reach: float) -> np.ndarray:
    """(6,) distance along x (m) from the front feet back to each foot at the stance's neutral point: 0 for the
    front legs, about 0.47 for the middle, 0.93 for the hind legs (Daisy, stance_reach 0.3 m)."""
    ahead = np.array([(leg.radius + stance_reach) * math.cos(leg.angle) for leg in spec.legs])
    return ahead.max() - ahead


def held_lift(trail_x: np.ndarray, trail_b: np.ndarray, x_now: float, lags: np.ndarray,
              window: float = WINDOW) -> np.ndarray:
    """(6,) the lowest lift per leg (rad): the largest b in the trail commanded within `window` of the base position
    x_now - lag (m), where the front feet stood over this leg's foot; 0 where none was, and for legs with a lag
    within `window` (the front legs follow the commanded b alone)."""
    trail_x, trail_b, lags = np.asarray(trail_x, dtype=float), np.asarray(trail_b, dtype=float), np.asarray(lags)
    if trail_x.size == 0:
        return np.zeros(len(lags))
    near = np.abs(trail_x[None, :] - (x_now - lags)[:, None]) <= window
    near &= (lags > window)[:, None]
    return np.where(near, trail_b[None, :], 0.0).max(axis=1)


class LiftTrail:
    """The (base x, commanded b) of each control step of an episode, and the lifts it gives each leg."""

    def __init__(self, lags: np.ndarray, capacity: int):
        self.lags = np.asarray(lags, dtype=float)
        self._x, self._b = np.empty(capacity), np.empty(capacity)
        self._n = 0

    def reset(self) -> None:
        self._n = 0

    def record(self, x: float, b: float) -> None:
        """Append one control step's base x (m) and commanded b (rad); the oldest sample is dropped when full."""
        if self._n == len(self._x):
            self._x[:-1], self._b[:-1] = self._x[1:].copy(), self._b[1:].copy()
            self._n -= 1
        self._x[self._n], self._b[self._n] = x, b
        self._n += 1

    def floor(self, x_now: float) -> np.ndarray:
        """(6,) the lowest lift per leg (rad) for the base at x_now: see `held_lift`."""
        return held_lift(self._x[: self._n], self._b[: self._n], x_now, self.lags)
