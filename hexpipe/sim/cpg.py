"""The paper's limit-cycle CPG (eqs. 1-2), six coupled oscillators, and the integration of its parameters.

Each leg i has an oscillator state (x_i, y_i) in joint space: x is the fore/aft hip angle, y the lift angle (rad).
With the ellipse H(x, y) = ((x - cx)/a)^2 + ((y - cy)/b)^2 (the paper's H + 1, so that 1 - H vanishes on the
cycle), the paper's dynamics are  d[x, y]/dt = omega * n + gamma * (1 - H) * t,  n the tangent and t the normal of
the ellipse. In raw radians the normal term's gain grows like 1/b^2 and explicit Euler at 240 Hz oscillates for
small a, b, so we integrate the same flow in normalised coordinates u = (x - cx)/a, v = (y - cy)/b, where
n = (-v, u), t = (u, v): each oscillator circulates counter-clockwise at exactly omega rad/s on the unit circle and
is pulled back to it at rate gamma. Changing a or b mid-stride rescales (x, y) continuously.

Tripod coupling (a fixed linear map on the stacked states): lambda * (mean_j R(phi_i - phi_j) z_j - z_i), with
phi = 0 for one tripod and pi for the other;
it vanishes once the tripods are locked in anti-phase,
so it does not change the period.
"""

from __future__ import annotations

import numpy as np

from hexpipe.config import CpgConfig

N_LEGS = 6


def tripod_phases(tripods: np.ndarray) -> np.ndarray:
    """Desired phase (rad) of each leg: 0 for tripod 0, pi for tripod 1."""
    return np.pi * np.asarray(tripods, dtype=float)


def coupling_matrix(phases: np.ndarray, coupling: float) -> np.ndarray:
    """The (2n, 2n) linear map z -> coupling * (mean_j R(phi_i - phi_j) z_j - z_i) on the flattened states."""
    n = len(phases)
    d = phases[:, None] - phases[None, :]
    c, s = np.cos(d), np.sin(d)
    blocks = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)  # (n, n, 2, 2): R[i, j]
    blocks[np.arange(n), np.arange(n)] = 0.0
    mean = blocks.transpose(0, 2, 1, 3).reshape(2 * n, 2 * n) / max(n - 1, 1)
    return coupling * (mean - np.eye(2 * n)) if n > 1 else np.zeros((2 * n, 2 * n))


def oscillator_derivative(z: np.ndarray, omega: float, gamma: float, coupling: np.ndarray) -> np.ndarray:
    """d/dt of the normalised states z (n, 2): rotation at omega, pull to the unit circle, tripod coupling."""
    radial = gamma * (1.0 - (z * z).sum(axis=1, keepdims=True))
    dz = radial * z
    dz[:, 0] -= omega * z[:, 1]
    dz[:, 1] += omega * z[:, 0]
    return dz + (coupling @ z.reshape(-1)).reshape(z.shape)


def step_oscillators(z: np.ndarray, omega: float, dt: float, gamma: float, coupling: np.ndarray) -> np.ndarray:
    """One midpoint (RK2) step of the normalised oscillators; stable for gamma*dt, omega*dt << 1."""
    k1 = oscillator_derivative(z, omega, gamma, coupling)
    k2 = oscillator_derivative(z + 0.5 * dt * k1, omega, gamma, coupling)
    return z + dt * k2


def locked_states(phases: np.ndarray, phase0: float = 0.0) -> np.ndarray:
    """Normalised states on the unit circle at the locked tripod phases, shifted by phase0 (rad)."""
    theta = phases + phase0
    return np.stack([np.cos(theta), np.sin(theta)], axis=1)


def joint_space(z: np.ndarray, a: float, b: float, center: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """(x, y) in radians from normalised states: x = cx + a*u, y = cy + b*v."""
    return np.stack([center[0] + a * z[:, 0], center[1] + b * z[:, 1]], axis=1)


def integrate_parameters(
    values: np.ndarray, rates: np.ndarray, accel: np.ndarray, dt: float, cfg: CpgConfig
) -> tuple[np.ndarray, np.ndarray]:
    """Integrate the second derivative `accel` of (a, b, omega) over dt with the rate and value bounds.

    A value that reaches a bound stops there with zero rate, so the policy never has to unwind a saturated rate.
    """
    lower, upper, rate_limit = cfg.lower, cfg.upper, cfg.rate_limit
    rates = np.minimum(np.maximum(rates + accel * dt, np.negative(rate_limit)), rate_limit)
    values = values + rates * dt
    hit = (values <= lower) | (values >= upper)
    if hit.any():
        values = np.minimum(np.maximum(values, lower), upper)
        rates = np.where(hit, 0.0, rates)
    return values, rates


class CPG:
    """Six coupled oscillators plus the (a, b, omega) parameters that the policy steers."""

    def __init__(self, cfg: CpgConfig, tripods: np.ndarray):
        self.cfg = cfg
        self.phases = tripod_phases(tripods)
        self._coupling = coupling_matrix(self.phases, cfg.coupling)
        self.z = locked_states(self.phases)
        self.params = np.asarray(cfg.initial, dtype=float)
        self.rates = np.zeros(3)

    def reset(self, params: np.ndarray, phase0: float = 0.0, z: np.ndarray | None = None) -> None:
        self.params = np.asarray(params, dtype=float).copy()
        self.rates = np.zeros(3)
        self.z = locked_states(self.phases, phase0) if z is None else np.asarray(z, dtype=float).copy()

    def step(self, accel: np.ndarray, dt: float) -> np.ndarray:
        """Advance parameters and oscillators by dt (s); returns the joint-space (x, y) of every leg (rad)."""
        self.params, self.rates = integrate_parameters(self.params, self.rates, accel, dt, self.cfg)
        self.z = step_oscillators(self.z, self.params[2], dt, self.cfg.convergence, self._coupling)
        return self.xy

    @property
    def xy(self) -> np.ndarray:
        return joint_space(self.z, self.params[0], self.params[1])
