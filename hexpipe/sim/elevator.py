"""An elevator reflex: a leg whose lower link touches something while it swings opens its elbow for the rest of that
swing, so the foot goes out and up instead of pressing on what holds it.

Why (issue 10): at a face 1.0 m deep the policies stall when a hind foot lands at the face's foot under a knee that
is already over the block. The shin then lies across the block's top edge; lifting the shoulder pivots the rigid
leg about that edge and presses the foot down and back, so no lift frees it (12 of the 13 stalls at a face over six
terrains, reports/experiments/README.md, "ahead150: where the wide block stops it"). Insects meet a swing that hits
something with the elevator reflex: the leg draws back from it and lifts higher. Here the elbow opens: in the
stance pose the shin points down, a little inward, so opening it moves the foot outward (backward, for a hind leg)
and up, and turns the shin away from an edge in front of it.

A leg counts as caught from a control step that ends with its lower link (shin or foot) pressed from the side,
by a contact whose normal leans more than 45 degrees from vertical (a face or an edge, not the ground a late foot
still drags on), while its oscillator is in the swing, until its next stance (y <= 0). Pure NumPy; the env reads
the contact normals after each control step and passes the caught legs to the gait map.
"""

from __future__ import annotations

import numpy as np

SIDE_COS = np.cos(np.radians(45.0))  # a contact normal with a vertical part below this presses from the side


def pressed_from_side(normals: list[np.ndarray], side_cos: float = SIDE_COS) -> np.ndarray:
    """(legs,) bool: per leg, whether any of its lower link's contact normals (points, 3), unit vectors pointing
    towards the robot, leans more than acos(side_cos) from vertical."""
    return np.array([bool(np.any(np.abs(n[:, 2]) < side_cos)) if len(n) else False for n in normals])


def caught_legs(caught: np.ndarray, y: np.ndarray, pressed: np.ndarray) -> np.ndarray:
    """(legs,) bool: the legs caught after this control step. `caught`: before it; `y`: each leg's oscillator y now
    (rad, > 0 in swing); `pressed`: each lower link pressed from the side now. A caught leg stays caught while it
    swings."""
    swinging = np.asarray(y) > 0.0
    return (np.asarray(caught, dtype=bool) | np.asarray(pressed, dtype=bool)) & swinging


def elbow_opening(y: np.ndarray, caught: np.ndarray, gain: float) -> np.ndarray:
    """(..., legs) elbow opening (rad, positive opens) for oscillator outputs y (..., legs): `gain` * y in a caught
    leg's swing, 0 in stance and for legs not caught."""
    return gain * np.maximum(np.asarray(y), 0.0) * np.asarray(caught, dtype=float)
