"""The paper's limit-cycle CPG (eqs. 1-2), six coupled oscillators, and the integration of its parameters.

Each leg i has an oscillator state (x_i, y_i) in joint space: x is the fore/aft hip angle, y the lift angle (rad).
With the ellipse H(x, y) = ((x - cx)/a)^2 + ((y - cy)/b)^2 (the paper's H + 1, so that 1 - H vanishes on the
cycle), the paper's dynamics are  d[x, y]/dt = omega * n + gamma * (1 - H) * t,  n the tangent and t the normal of
the ellipse. In raw radians the normal term's gain grows like 1/b^2 and explicit Euler at 240 Hz oscillates for
small a, b, so we integrate the same flow in normalised coordinates u = (x - cx)/a, v = (y - cy)/b, where
n = (-v, u), t = (u, v): each oscillator circulates counter-clockwise at exactly omega rad/s on the unit circle and
is pulled back to it at rate gamma. Changing a or b mid-stride rescales (x, y) continuously.

Tripod coupling (a fixed linear map on the states): lambda * (mean_j R(phi_i - phi_j) z_j - z_i), with phi = 0 for
one tripod and pi for the other; it vanishes once the tripods are locked in anti-phase, so it does not change the
period.

How it is integrated. With z = u + i v complex, the flow is  dz/dt = i omega z + gamma (1 - |z|^2) z + C z, and C
(complex-linear) commutes with rotations. So z = exp(i theta) w, theta = integral of omega, and w follows the
slow, omega-free flow gamma (1 - |w|^2) w + C w. Each of the three parts has an exact solution: the rotation, the
radial pull (|w|^2 is logistic in time) and the coupling (a matrix exponential). `CPG.advance` composes them
(Lie splitting) over one control step, for all physics substeps at once. On the locked cycle, where the radial and
coupling terms vanish, this is exact; elsewhere it is first order in the control step and unconditionally stable
(each part is exact and contractive), so off-cycle starts converge for any step.
"""

from __future__ import annotations

import numpy as np

from hexpipe.config import CpgConfig


def tripod_phases(tripods: np.ndarray) -> np.ndarray:
    """Desired phase (rad) of each leg: 0 for tripod 0, pi for tripod 1."""
    return np.pi * np.asarray(tripods, dtype=float)


def coupling_matrix(phases: np.ndarray, coupling: float) -> np.ndarray:
    """The complex (n, n) map z -> coupling * (mean_{j != i} exp(i (phi_i - phi_j)) z_j - z_i)."""
    n = len(phases)
    if n < 2:
        return np.zeros((n, n), dtype=complex)
    rot = np.exp(1j * (phases[:, None] - phases[None, :]))
    np.fill_diagonal(rot, 0.0)
    return coupling * (rot / (n - 1) - np.eye(n))


def coupling_flows(coupling: np.ndarray, dt: float, n: int) -> np.ndarray:
    """exp(C k dt) for k = 1..n: the exact coupling flow over each substep's time since the control step began."""
    lam, vec = np.linalg.eigh(coupling)  # C is Hermitian: exp(i(phi_i - phi_j)) = conj(exp(i(phi_j - phi_i)))
    t = dt * np.arange(1, n + 1)
    return np.einsum("ij,kj,lj->kil", vec, np.exp(lam[None, :] * t[:, None]), vec.conj())


def radial_flow(w: np.ndarray, gamma: float, t: np.ndarray) -> np.ndarray:
    """Exact solution of dw/dt = gamma (1 - |w|^2) w after each time in t (s); w (..., n) complex.

    |w|^2 = q follows dq/dt = 2 gamma (1 - q) q, so q(t) = q0 / (q0 + (1 - q0) exp(-2 gamma t)); the phase is kept.
    """
    q0 = w.real**2 + w.imag**2
    decay = np.exp(-2.0 * gamma * t)
    return w / np.sqrt(q0 + (1.0 - q0) * decay[:, None])


def locked_states(phases: np.ndarray, phase0: float = 0.0) -> np.ndarray:
    """Complex states on the unit circle at the locked tripod phases, shifted by phase0 (rad)."""
    return np.exp(1j * (phases + phase0))


def integrate_parameters(
    values: np.ndarray, rates: np.ndarray, command: np.ndarray, dt: float, cfg: CpgConfig
) -> tuple[np.ndarray, np.ndarray]:
    """Integrate (a, b, omega) over dt under `command`: their second derivative (cfg.action_order 2, the paper's) or
    their rate (1), with the rate and value bounds.

    A value that reaches a bound stops there with zero rate, so the policy never has to unwind a saturated rate.
    Rates stay within [-cfg.falling_limit, cfg.rate_limit].
    """
    lower, upper, rate_limit = cfg.lower, cfg.upper, cfg.rate_limit
    wanted = command if cfg.action_order == 1 else rates + command * dt
    rates = np.minimum(np.maximum(wanted, np.negative(cfg.falling_limit)), rate_limit)
    values = values + rates * dt
    hit = (values <= lower) | (values >= upper)
    if hit.any():
        values = np.minimum(np.maximum(values, lower), upper)
        rates = np.where(hit, 0.0, rates)
    return values, rates


def parameter_path(
    values: np.ndarray, rates: np.ndarray, command: np.ndarray, dt: float, n: int, cfg: CpgConfig
) -> tuple[np.ndarray, np.ndarray]:
    """`integrate_parameters` applied n times: (n, 3) values and rates after each substep.

    Plain floats: three parameters times a few substeps is cheaper in Python than in small NumPy calls.
    """
    out_v, out_r = np.empty((n, 3)), np.empty((n, 3))
    first_order = cfg.action_order == 1
    for j in range(3):
        v, r = float(values[j]), float(rates[j])
        step = float(command[j]) if first_order else float(command[j]) * dt  # the rate, or its change per substep
        lo, hi, lim, fall = cfg.lower[j], cfg.upper[j], cfg.rate_limit[j], cfg.falling_limit[j]
        for k in range(n):
            r = min(max(step if first_order else r + step, -fall), lim)
            v += r * dt
            if v <= lo or v >= hi:
                v, r = min(max(v, lo), hi), 0.0
            out_v[k, j], out_r[k, j] = v, r
    return out_v, out_r


class CPG:
    """Six coupled oscillators plus the (a, b, omega) parameters that the policy steers."""

    def __init__(self, cfg: CpgConfig, tripods: np.ndarray):
        self.cfg = cfg
        self.phases = tripod_phases(tripods)
        self._coupling = coupling_matrix(self.phases, cfg.coupling)
        self._flows: dict[tuple[float, int], np.ndarray] = {}
        self.w = locked_states(self.phases)  # complex normalised states u + i v
        self.params = np.asarray(cfg.initial, dtype=float)
        self.rates = np.zeros(3)

    def reset(self, params: np.ndarray, phase0: float = 0.0, z: np.ndarray | None = None) -> None:
        """z: optional (6, 2) normalised (u, v) start states; default: locked on the cycle, shifted by phase0."""
        self.params = np.asarray(params, dtype=float).copy()
        self.rates = np.zeros(3)
        if z is None:
            self.w = locked_states(self.phases, phase0)
        else:
            z = np.asarray(z, dtype=float)
            self.w = z[:, 0] + 1j * z[:, 1]

    def drop_lift(self) -> None:
        """Set the lift b to its floor (`cfg.lower`) and stop its rate: a training perturbation
        (`hexpipe.rl.perturbations`). The legs follow the new b from the next substep; a and omega are untouched."""
        self.params[1] = self.cfg.lower[1]
        self.rates[1] = 0.0

    def advance(
        self, command: np.ndarray, dt: float, n: int, lift_floor: np.ndarray | None = None,
        stride_cap: float | None = None,
    ) -> np.ndarray:
        """Advance n substeps of dt (s) under a constant `command` (the parameters' second derivative, or their rate
        with cfg.action_order 1); returns (n, 6, 2) joint-space (x, y) (rad).

        lift_floor: optional (6,) lowest lift per leg (rad); a leg swings with the larger of it and b
        (`hexpipe.sim.lift_trail`, the lift reflex). stride_cap: optional longest stride (rad); the legs swing with
        the smaller of it and a (the stride reflex). The parameters themselves are unchanged.
        """
        values, rates = parameter_path(self.params, self.rates, command, dt, n, self.cfg)
        self.params, self.rates = values[-1].copy(), rates[-1].copy()
        key = (dt, n)
        if key not in self._flows:
            self._flows[key] = coupling_flows(self._coupling, dt, n)
        w = radial_flow(self._flows[key] @ self.w, self.cfg.convergence, dt * np.arange(1, n + 1))
        z = np.exp(1j * dt * np.cumsum(values[:, 2]))[:, None] * w
        self.w = z[-1]
        lift = values[:, 1:2] if lift_floor is None else np.maximum(values[:, 1:2], lift_floor[None, :])
        stride = values[:, :1] if stride_cap is None else np.minimum(values[:, :1], stride_cap)
        return np.stack([stride * z.real, lift * z.imag], axis=-1)

    def step(self, command: np.ndarray, dt: float) -> np.ndarray:
        """Advance one substep of dt (s); returns the joint-space (x, y) of every leg (rad)."""
        return self.advance(command, dt, 1)[0]

    @property
    def z(self) -> np.ndarray:
        """(6, 2) normalised states (u, v) = ((x - cx) / a, (y - cy) / b)."""
        return np.stack([self.w.real, self.w.imag], axis=1)

    @property
    def xy(self) -> np.ndarray:
        """(6, 2) joint-space (x, y) now (rad)."""
        return np.stack([self.params[0] * self.w.real, self.params[1] * self.w.imag], axis=1)
