"""Flat ground, per trial: the policy's mean time to the goal (s), the share of its control steps with b above
0.22 rad (its floor is 0.2), its highest b, and how far behind the fixed gait it is (s, mean over episodes) when
it first reaches 1, 2 and 3 m, for `long_stride` and `pinned_stride` on the same six seeds.

Reads each trial's evaluation traces (data/sweeps/<sweep>/<trial>/eval/cpg_traces.csv.gz, written by the sweep):

    .venv/bin/python reports/experiments/long_stride/flat_lift.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd

SEEDS = (1, 1001, 2001, 2, 1002, 2002)
SWEEPS = (("long_stride", "long_stride"), ("stride_reflex", "pinned_stride"))
LIFTED = 0.22  # rad: b this far above its floor of 0.2 counts as a lift
MARKS = (1.0, 2.0, 3.0)  # m from the start


def _arrival(traces: pd.DataFrame) -> np.ndarray:
    """Mean over episodes of the first time (s) each mark is reached."""
    firsts = [[g.time[g.distance >= m].min() for m in MARKS] for _, g in traces.groupby("episode")]
    return pd.DataFrame(firsts).mean().to_numpy()


def main() -> int:
    for sweep, condition in SWEEPS:
        for seed in SEEDS:
            path = Path(f"data/sweeps/{sweep}/{condition}-seed{seed}/eval/cpg_traces.csv.gz")
            if not path.is_file():
                print(f"error: {path} is missing; run the sweep's command first", file=sys.stderr)
                return 1
            traces = pd.read_csv(path, usecols=["terrain", "controller", "episode", "time", "distance", "b"])
            flat = traces[traces.terrain == "flat"]
            policy = flat[flat.controller == "policy"]
            goal = policy.groupby("episode").time.max().mean()
            behind = _arrival(policy) - _arrival(flat[flat.controller == "best_fixed"])
            print(f"{condition:14s} seed {seed:5d}: flat time {goal:.2f} s, share of steps with b > {LIFTED} "
                  f"{(policy.b > LIFTED).mean():.3f}, highest b {policy.b.max():.2f}, behind the fixed gait at "
                  + ", ".join(f"{m:g} m {s:+.2f} s" for m, s in zip(MARKS, behind, strict=True)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
