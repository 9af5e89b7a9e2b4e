"""Reward terms as small pure functions; the env adds them up and reports each one in `info["reward_terms"]`."""

from __future__ import annotations

GRAVITY = 9.81  # m/s^2


def forward_velocity_reward(dx: float, dt: float, scale: float) -> float:
    """The paper's reward: scale * forward velocity (m/s) over the last control step."""
    return scale * dx / dt


def power_penalty(power_w: float, cost: float) -> float:
    """Minus `cost` reward per watt of mechanical joint power: makes a needlessly high or fast gait cost something.

    0 (the paper's reward) leaves stepping high free on this robot, so a policy has no reason to lower its feet
    once it has learned to lift them.
    """
    return -cost * power_w


def cost_of_transport(energy_j: float, mass_kg: float, distance_m: float) -> float:
    """Dimensionless cost of transport E / (m g d): the energy spent per unit weight and distance travelled."""
    return energy_j / (mass_kg * GRAVITY * max(distance_m, 1e-3))
