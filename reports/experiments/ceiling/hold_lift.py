"""Is the stall at extra blocks' second face the policy's choice or the gait's limit? Evaluate's episodes of one
terrain, run as observed and again with the policy's b (and optionally omega) overridden once the base is past
--from metres: b is driven to its ceiling and held there; with --omega W, omega is also steered to W rad/s.

    .venv/bin/python reports/experiments/ceiling/hold_lift.py POLICY_DIR ... [--terrain extra_blocks]
        [--episodes 10] [--from 1.2] [--omega 4.712389] [--zone] [--set section.key=value ...]

--zone runs, beside the observed episodes, one other arm: b driven to its ceiling wherever the true terrain in
task.lift_free_zone (0.6 m behind the base to 0.7 m ahead) rises or falls by more than 3 cm (where the lift price is
waived), on any terrain: a reflex that lifts wherever the feet meet uneven ground, the structural lever the
straddle points to, tried on trained policies before it is built into training.

From 1.2 m on extra blocks the front feet are 0.5 m before the second face (2.0 m) and the hind feet leave the
first block's top. A fixed gait at a 0.4, b 0.5 crosses extra blocks 18 of 20 at omega pi and 20 of 20 at 1.5 pi
(`fixed_gaits.py`, `hard20.txt`); the policies that fail stall with b at 0.5 and omega at its floor, then let b
fall (`trace_seed2_ep0.txt`). If holding b at the ceiling mends the failures, the policy's falling b is what fails;
if it needs omega too, the stall is the gait's at that speed. The policies are not retrained. Prints success per
arm and the distances of the failures.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from episodes import checked_inputs, policy_episode, print_arms  # the helper beside this script

from hexpipe.envs import hexapod
from hexpipe.envs.rewards import lift_waived
from hexpipe.sensors.heightmap import quat_to_yaw

_step = hexapod.HexapodEnv.step
OMEGA_GAIN, OMEGA_DAMPING = 4.0, 2.0  # the action (omega's acceleration, in [-1, 1]) steering omega to its target


def _lifted(action) -> np.ndarray:
    """A copy of the action with b's acceleration at +1: b rises to its ceiling and stays there."""
    action = np.array(action, dtype=float, copy=True)
    action[1] = 1.0
    return action


def _override(start: float, omega: float | None):
    def step(self, action):  # the env's own step, the policy's action replaced past `start`
        if self._last_x - self.start_xy[0] >= start:
            action = _lifted(action)
            if omega is not None:
                error, rate = omega - float(self.cpg.params[2]), float(self.cpg.rates[2])
                action[2] = float(np.clip(OMEGA_GAIN * error - OMEGA_DAMPING * rate, -1.0, 1.0))
        return _step(self, action)
    return step


def _zone_hold(self, action):  # the env's own step, b driven up while the feet's reach holds uneven terrain
    pos, quat = self.robot.base_state()[:2]
    relief = self.terrain.relief(float(pos[0]), float(pos[1]), quat_to_yaw(quat), *self.task.lift_free_zone)
    return _step(self, _lifted(action) if lift_waived(relief) else action)


ARMS = ("observed", "b held", "b held, omega steered")
ZONE_ARMS = ("observed", "b held in the zone")


def _one(job: tuple[str, str, int, str, float, float, tuple[str, ...]]) -> tuple[bool, float]:
    policy, terrain, index, arm, start, omega, overrides = job
    hexapod.HexapodEnv.step = {"observed": _step, "b held": _override(start, None),
                               "b held, omega steered": _override(start, omega), "b held in the zone": _zone_hold}[arm]
    return policy_episode(policy, terrain, index, overrides)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("policies", nargs="+")
    ap.add_argument("--terrain", default="extra_blocks")
    ap.add_argument("--episodes", type=int, default=10)
    ap.add_argument("--from", dest="start", type=float, default=1.2)
    ap.add_argument("--omega", type=float, default=1.5 * np.pi)
    ap.add_argument("--zone", action="store_true", help="the observed arm and the zone reflex only")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    params = checked_inputs(a.overrides, [a.terrain], a.policies)
    arms = ZONE_ARMS if a.zone else ARMS
    if a.zone:
        if params.task.lift_free_zone is None:
            raise SystemExit("error: --zone reads task.lift_free_zone, which is null; set it, e.g. [0.6, 0.7]")
        behind, ahead = params.task.lift_free_zone
        print(f"{a.terrain}, {a.episodes} episodes; b driven to its ceiling ({params.cpg.upper[1]} rad) wherever the "
              f"terrain {behind} m behind to {ahead} m ahead of the base is uneven")
    else:
        print(f"{a.terrain}, {a.episodes} episodes; from {a.start} m on: b driven to its ceiling "
              f"({params.cpg.upper[1]} rad), omega steered to {a.omega:.3f} rad/s in the last arm")
    jobs = [(p, a.terrain, i, arm, a.start, a.omega, tuple(a.overrides)) for p in a.policies for arm in arms
            for i in range(a.episodes)]
    with ProcessPoolExecutor(a.workers) as pool:
        print_arms(a.policies, arms, a.episodes, list(pool.map(_one, jobs)))


if __name__ == "__main__":
    main()
