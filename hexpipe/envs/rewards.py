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


def lift_penalty(b_rad: float, floor_rad: float, cost: float) -> float:
    """Minus `cost` reward per rad of the CPG's lift b above its floor (cpg.lower's b), each control step.

    On this robot a high lift costs little joint power (on flat ground, policies walking at b 0.31 rad spent
    679 J an episode against 645 J at 0.25, 5% more: reports/experiments/select), so under the power price alone
    walking high everywhere earns as much on the training terrains as lifting only at faces. This prices the lift
    itself, as a stand-in for what a real leg's swing height costs (motor heat, impacts, a taller body's risk).
    """
    return -cost * max(0.0, b_rad - floor_rad)


def lift_shortfall_penalty(b_rad: float, reflex_rad: float, cost: float) -> float:
    """Minus `cost` reward per rad the CPG's lift b falls short of the lift reflex's (task.lift_teacher), each
    control step.

    The reflex lifts to b's ceiling only where the height map shows relief ahead or under the feet, so this is 0 on
    level ground (where the lift price pushes b down) and asks for a lift at faces: a dense signal for what a sparse
    crossing reward teaches slowly, from the same map the policy sees.
    """
    return -cost * max(0.0, reflex_rad - b_rad)


def stride_deviation_penalty(a_rad: float, reflex_rad: float, cost: float) -> float:
    """Minus `cost` reward per rad the CPG's stride a lies from the stride reflex's (task.stride_teacher), each
    control step.

    Both ways: the reflex asks for the long stride on open ground and at single faces, where it is faster, and for
    the short one only at a straddle of two blocks, which the long stride fails (hexpipe/sim/stride_reflex.py).
    """
    return -cost * abs(a_rad - reflex_rad)


def time_penalty(dt: float, cost: float) -> float:
    """Minus `cost` reward per s of episode time, for a control step of `dt` s.

    The forward reward pays scale * dx / dt per step, so an episode's undiscounted sum is scale * distance / dt
    whatever its speed: on flat ground a fixed gait at a 0.3 rad earns what one at 0.4 does, 3 s later, for about
    the same energy (cost of transport 1.06 against 1.02: reports/experiments/time/return_terms.txt). Only the
    discount asks for speed. A price per second makes a slower crossing cost what it costs in the evaluation's time
    to goal.
    """
    return -cost * dt


RELIEF_M = 0.03  # m of rise or fall within the lift-free zone (task.lift_free_zone) that waives the lift price


def lift_waived(relief_m: float) -> bool:
    """Whether the terrain around the body is uneven enough (more than RELIEF_M of relief, m) that lifting the feet
    is what it asks for, so the lift price is not charged there (task.lift_free_zone)."""
    return relief_m > RELIEF_M


def ramp(step: int, start: int, end: int) -> float:
    """The share of a price in force at training `step`: 0 before `start`, rising linearly to 1 at `end`."""
    return min(1.0, max(0.0, (step - start) / (end - start)))


FAILURES = ("stuck", "fall")  # terminations that are the gait's fault; the goal and the time limit are not


def failure_penalty(termination: str | None, penalty: float) -> float:
    """Minus `penalty` reward once, on the step that ends the episode stuck or fallen; 0 on every other step.

    With a power price, reward near a block can turn negative (slow progress, high power): a policy then gains by
    ending the episode against the face, since "stuck" stops the costs. The penalty makes giving up cost more than
    a slow, expensive climb.
    """
    return -penalty if termination in FAILURES else 0.0


def cost_of_transport(energy_j: float, mass_kg: float, distance_m: float) -> float:
    """Dimensionless cost of transport E / (m g d): the energy spent per unit weight and distance travelled."""
    return energy_j / (mass_kg * GRAVITY * max(distance_m, 1e-3))
