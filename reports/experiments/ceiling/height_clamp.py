"""Does the policy's lift key on its height above the terrain under the base? Evaluate's episodes of one terrain,
run as observed and again with that reading (the body vector's first entry without position) held at a constant.

    .venv/bin/python reports/experiments/ceiling/height_clamp.py TERRAIN POLICY_DIR ... [--episodes 10]
        [--height 0.235] [--set section.key=value ...]

The default constant, 0.235 m, is the base's height above flat ground while walking (`trace.py ... flat 0`: 0.23-0.24
at every sample). Over a block's top with the feet below it the reading falls to about 0.16; over the gap after a
block, with the hind feet still on it, it rises to 0.26-0.31 (`trace_seed2_ep0.txt`). The policies are not
retrained: this asks what each one does with the reading taken away. Prints success as observed and clamped, and
the distances of the failures.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

from episodes import checked_inputs, policy_episode  # the helper beside this script

from hexpipe.envs import hexapod

_observed = hexapod.HexapodEnv._observation


def _clamp_height(height: float):
    def observation(self):  # the env's own observation, the height reading replaced
        obs = _observed(self)
        obs["body"] = obs["body"].copy()
        obs["body"][0] = height
        return obs
    return observation


def _one(job: tuple[str, str, int, float | None, tuple[str, ...]]) -> tuple[bool, float]:
    policy, terrain, index, height, overrides = job
    hexapod.HexapodEnv._observation = _observed if height is None else _clamp_height(height)
    return policy_episode(policy, terrain, index, overrides)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("terrain")
    ap.add_argument("policies", nargs="+")
    ap.add_argument("--episodes", type=int, default=10)
    ap.add_argument("--height", type=float, default=0.235)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    params = checked_inputs(a.overrides, [a.terrain], a.policies)
    if params.task.observe_position:
        raise SystemExit("error: task.observe_position is true: the body's first entry is x, not the height")
    print(f"{a.terrain}, {a.episodes} episodes; height held at {a.height} m")
    print("policy                                         observed  clamped  failures (m): observed | clamped")
    jobs = [(p, a.terrain, i, h, tuple(a.overrides)) for p in a.policies for h in (None, a.height)
            for i in range(a.episodes)]
    with ProcessPoolExecutor(a.workers) as pool:
        out = iter(list(pool.map(_one, jobs)))
    for policy in a.policies:
        seen, held = ([next(out) for _ in range(a.episodes)] for _ in range(2))
        fails = [" ".join(f"{d:.2f}" for ok, d in runs if not ok) for runs in (seen, held)]
        counts = [f"{sum(ok for ok, _ in runs):>4}/{a.episodes:<3}" for runs in (seen, held)]
        print(f"{policy:<46} {counts[0]} {counts[1]}  {fails[0]} | {fails[1]}")


if __name__ == "__main__":
    main()
