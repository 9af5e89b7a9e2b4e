"""The physical premise, measured: fixed open-loop gaits (zero action) on flat ground and the training block,
with the cost of transport of each run (what `task.power_cost` charges for).

Usage: python benchmarks/premise.py [--seeds 2] [--out reports/premise.json] [--sim KEY=VALUE ...]

The physics is `SimConfig`'s defaults (those of params.yaml); `--sim` tries other settings without touching
params.yaml, e.g. `--sim physics_hz=240 --sim solver_iterations=50 --sim position_gain=0.3` (before issue 12).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from fixed_gait import fixed_gait_episode

from hexpipe.atomic import write_json
from hexpipe.config import SimConfig

# (terrain, a, b) at omega = 1.5 pi: the default stride, then the long stride the policies choose
CASES = [("flat", 0.25, 0.15), ("flat", 0.25, 0.40), ("single_block", 0.25, 0.15), ("single_block", 0.25, 0.30),
         ("single_block", 0.25, 0.40), ("flat", 0.40, 0.15), ("flat", 0.40, 0.50)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("reports/premise.json"))
    parser.add_argument("--sim", action="append", default=[], metavar="KEY=VALUE", help="a SimConfig override")
    args = parser.parse_args()
    sim = SimConfig(**dict(kv.split("=", 1) for kv in args.sim))
    print(sim)
    rows = [fixed_gait_episode(t, a, b, s, sim) for t, a, b in CASES for s in range(args.seeds)]
    for r in rows:
        print(f"{r['terrain']:13s} a={r['a']:.2f} b={r['b']:.2f} seed={r['seed']}: {r['termination']} "
              f"after {r['distance_m']:.2f} m in {r['time_s']:.1f} s, cost of transport {r['cost_of_transport']:.2f}")
    write_json(args.out, {"sim": sim.model_dump(mode="json"), "episodes": rows})


if __name__ == "__main__":
    main()
