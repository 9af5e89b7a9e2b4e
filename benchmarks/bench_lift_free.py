"""What the lift-free zone (`task.lift_free_zone`) costs on the hot path: env.step with it, without it, and the
zone's check alone.

Usage: python benchmarks/bench_lift_free.py [--windows 9] [--steps 100] [--terrain single_block]

Four envs, the default config each but for the lift price and its zone (off; on at [0.4, 0.5] m; on while
ppo.lift_cost_ramp holds the price's share at 0, when the check is skipped; the price alone, the default's hot
path), stepped with the same seeded random actions in interleaved windows on one core; medians
are compared, so machine noise hits all alike. The check itself (one `Terrain.relief` over a 19 x 3 strip) is also
timed directly, which is the sharper number: an env step is mostly physics.
"""

from __future__ import annotations

import sys
import timeit
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_lift_trail import arguments, interleaved_step_ms

from hexpipe.config import TaskConfig
from hexpipe.envs.hexapod import HexapodEnv

# name: (task.lift_cost, task.lift_free_zone, the price's share now)
ZONES = {"zone on": (10.0, (0.4, 0.5), 1.0), "ramp at 0": (10.0, (0.4, 0.5), 0.0), "zone off": (10.0, None, 1.0),
         "no price": (0.0, None, 1.0)}


def main() -> None:
    args = arguments(__doc__.splitlines()[0], "single_block")
    envs = {name: HexapodEnv(args.terrain, task=TaskConfig(sensors=(), lift_cost=cost, lift_free_zone=zone))
            for name, (cost, zone, _) in ZONES.items()}
    for name, (_, _, share) in ZONES.items():
        envs[name].set_lift_cost_share(share)
    step_ms = interleaved_step_ms(envs, args.windows, args.steps)
    base = step_ms["no price"]
    print(f"env.step on {args.terrain}, medians of {args.windows} windows of {args.steps} steps:")
    for name, ms in step_ms.items():
        print(f"  {name:9s} {ms:.3f} ms ({100 * (ms / base - 1):+.1f}% against no price)")
    for name, env in envs.items():
        pos, quat, *_ = env.robot.base_state()
        check = min(timeit.repeat(lambda env=env, pos=pos, quat=quat: env._lift_free(pos, quat), number=2000,
                                  repeat=5)) / 2000
        print(f"  the zone's check alone, {name}: {1e6 * check:.1f} us a step")


if __name__ == "__main__":
    main()
