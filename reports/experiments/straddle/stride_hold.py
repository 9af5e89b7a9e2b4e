"""Would the straddle's short stride have carried the trained policies over extra blocks? Evaluate's episodes of one
terrain, run as observed and again with the policy's stride a steered to the stride reflex's (task.stride_teacher's
target: cpg.lower's a while the height map shows two raised regions in the feet's reach, cpg.upper's elsewhere).

    .venv/bin/python reports/experiments/straddle/stride_hold.py POLICY_DIR ... [--terrain extra_blocks]
        [--episodes 10] [--set section.key=value ...]

The policies are not retrained; b and omega stay theirs. The --set overrides must give the settings the policies
were trained under with the stride teacher on (it builds the reflex), e.g. the `straddle` condition's. Prints
success per arm and the distances (m) of the failures. If steering a mends the failures, the stride the teacher
asked for is what the policies missed; if not, the short stride is not enough for a learned lift.
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ceiling"))
from episodes import checked_inputs, policy_episode, print_arms  # the helper in ../ceiling

from hexpipe.envs import hexapod

_step = hexapod.HexapodEnv.step
GAIN, DAMPING = 40.0, 8.0  # the action (a's acceleration, in [-1, 1]) steering a to the reflex's stride


def _steered(self, action):  # the env's own step, a's acceleration replaced by one toward the reflex's stride
    action = np.array(action, dtype=float, copy=True)
    error, rate = self.stride_reflex.level - float(self.cpg.params[0]), float(self.cpg.rates[0])
    action[0] = float(np.clip(GAIN * error - DAMPING * rate, -1.0, 1.0))
    return _step(self, action)


ARMS = {"observed": _step, "a steered to the reflex": _steered}


def _one(job: tuple[str, str, int, str, tuple[str, ...]]) -> tuple[bool, float]:
    policy, terrain, index, arm, overrides = job
    hexapod.HexapodEnv.step = ARMS[arm]
    return policy_episode(policy, terrain, index, overrides)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("policies", nargs="+")
    ap.add_argument("--terrain", default="extra_blocks")
    ap.add_argument("--episodes", type=int, default=10)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    params = checked_inputs(a.overrides, [a.terrain], a.policies)
    if params.task.stride_teacher <= 0:
        raise SystemExit("error: task.stride_teacher is 0, so the env builds no stride reflex; --set it, e.g. "
                         "task.stride_teacher=100")
    print(f"{a.terrain}, {a.episodes} episodes; a steered to the stride reflex's ({params.cpg.lower[0]} rad at a "
          f"straddle, {params.cpg.upper[0]} elsewhere)")
    jobs = [(p, a.terrain, i, arm, tuple(a.overrides)) for p in a.policies for arm in ARMS for i in range(a.episodes)]
    with ProcessPoolExecutor(a.workers) as pool:
        print_arms(a.policies, list(ARMS), a.episodes, list(pool.map(_one, jobs)), policy_width=44, arm_width=23)


if __name__ == "__main__":
    main()
