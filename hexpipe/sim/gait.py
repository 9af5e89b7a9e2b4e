"""From oscillator states (x, y) to the 18 joint targets; pure NumPy.

The CPG circulates counter-clockwise, so x decreases while y > 0 (swing) and increases while y < 0 (stance).
We therefore read x as the *backward* hip angle: in stance the foot sweeps back and the body moves forward.
- hip yaw = sign(sin(mount angle)) * x  (a positive yaw moves a left leg's foot backward, a right leg's forward);
- stance (y <= 0): shoulder and elbow hold the inverse-kinematics solution that puts the foot on the stance plane
  `body_height` below the base at `stance_reach` from the yaw axis (the stance rule: feet stay on the ground);
- swing (y > 0): the shoulder lifts by lift_gain * y above that stance angle, the elbow keeps its stance angle
  unless the elevator reflex opens it (`hexpipe.sim.elevator`, a leg caught in its swing);
- targets then move no faster than the actuators' rated speeds (`slew_limit`).
"""

from __future__ import annotations

import math

import numpy as np

from hexpipe.sim.robot import RobotSpec


def leg_ik(reach: float, drop: float, upper: float, lower: float) -> tuple[float, float]:
    """Shoulder and elbow angles (rad, positive raises) that put the foot `reach` out and `drop` below the shoulder.

    Knee-up solution, as on Daisy. Raises ValueError if the point is out of the leg's workspace.
    """
    d2 = reach * reach + drop * drop
    cos_elbow = (d2 - upper * upper - lower * lower) / (2 * upper * lower)
    if not -1.0 <= cos_elbow <= 1.0:
        raise ValueError(f"foot target reach={reach} m, drop={drop} m is outside the leg's workspace")
    elbow = -math.acos(cos_elbow)
    shoulder = math.atan2(-drop, reach) - math.atan2(lower * math.sin(elbow), upper + lower * math.cos(elbow))
    return shoulder, elbow


def slew_limit(previous: np.ndarray, target: np.ndarray, max_step: np.ndarray) -> np.ndarray:
    """Move each joint target from `previous` towards `target` by at most `max_step` (rad).

    This is the actuators' speed limit (max_step = speed * dt): a high lift at a high frequency cannot be
    tracked, so stepping high costs stride speed, as on the real robot.
    """
    return previous + np.minimum(np.maximum(target - previous, -max_step), max_step)


def slew_path(previous: np.ndarray, targets: np.ndarray, max_step: np.ndarray) -> np.ndarray:
    """`slew_limit` along a sequence: targets (n, joints) -> the (n, joints) limited targets, one per substep."""
    out = np.empty_like(targets)
    current = previous
    for k, target in enumerate(targets):
        current = out[k] = slew_limit(current, target, max_step)
    return out


class GaitMap:
    """Maps the six (x, y) oscillator outputs of one time step to 18 joint targets (rad)."""

    def __init__(self, spec: RobotSpec, body_height: float, stance_reach: float, lift_gain: float = 1.0):
        self.lift_gain = lift_gain
        drop = body_height - spec.foot_radius
        self.stance_shoulder, self.stance_elbow = leg_ik(
            stance_reach - spec.bracket_length, drop, spec.upper_length, spec.lower_length
        )
        self.yaw_sign = np.array([math.copysign(1.0, math.sin(leg.angle)) for leg in spec.legs])

    def joint_targets(self, xy: np.ndarray, elbow_open: np.ndarray | None = None,
                      stride_scale: np.ndarray | None = None) -> np.ndarray:
        """xy: (..., 6, 2) oscillator outputs (rad) -> (..., 18) targets ordered yaw, shoulder, elbow per leg.

        Leading axes (e.g. the physics substeps of one control step) are kept, so a whole step maps at once.
        `elbow_open` (..., 6) rad, broadcast against xy's legs: how far each elbow opens from its stance angle.
        `stride_scale` (6,): a factor on each leg's fore/aft swing (the heading reflex, `hexpipe.sim.heading`).
        """
        xy = np.asarray(xy)
        targets = np.empty((*xy.shape[:-1], 3))
        sweep = self.yaw_sign if stride_scale is None else self.yaw_sign * stride_scale
        targets[..., 0] = sweep * xy[..., 0]
        targets[..., 1] = self.stance_shoulder + self.lift_gain * np.maximum(xy[..., 1], 0.0)
        targets[..., 2] = self.stance_elbow if elbow_open is None else self.stance_elbow + elbow_open
        return targets.reshape(*xy.shape[:-2], -1)
