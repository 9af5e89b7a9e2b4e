"""Two conditions of one sweep on their trials' own validation episodes (the 60 held-out `varied` episodes each trial
scores itself on, `ppo/selection.json`), paired by training seed: success and mean return, a minus b, with a
bootstrap interval over whole seeds.

    .venv/bin/python reports/experiments/lift_drops/validation.py reports/sweeps/lift_drops --a drops --b default
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from hexpipe.sweep.stats import bootstrap_mean


def validation(sweep: Path, condition: str) -> dict[int, dict[str, float]]:
    """Seed -> the trial's validation figures, for every trial of `condition` that has them."""
    out = {}
    for path in sorted(sweep.glob(f"{condition}-seed*/ppo/selection.json")):
        data = json.loads(path.read_text())
        seed = int(data["chosen_seed"])
        out[seed] = data["candidates"][str(seed)]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sweep", type=Path)
    ap.add_argument("--a", required=True, help="condition a")
    ap.add_argument("--b", required=True, help="condition b")
    args = ap.parse_args()
    a, b = validation(args.sweep, args.a), validation(args.sweep, args.b)
    seeds = sorted(set(a) & set(b))
    if not seeds:
        sys.exit(f"{args.sweep}: no seed has validation figures for both {args.a} and {args.b}")
    print(f"{'seed':>6} {args.a + ' success':>16} {args.b + ' success':>16} {args.a + ' return':>15} "
          f"{args.b + ' return':>15}")
    for s in seeds:
        print(f"{s:>6} {a[s]['success']:>16.3f} {b[s]['success']:>16.3f} {a[s]['return']:>15.1f} "
              f"{b[s]['return']:>15.1f}")
    for key in ("success", "return", "b_mean"):
        diff = np.array([a[s][key] - b[s][key] for s in seeds])
        est = bootstrap_mean([diff])
        print(f"{key}: {args.a} {np.mean([a[s][key] for s in seeds]):.3f}, {args.b} "
              f"{np.mean([b[s][key] for s in seeds]):.3f}; paired {args.a} minus {args.b} {est.value:+.3f} "
              f"[{est.low:+.3f}, {est.high:+.3f}] over {len(seeds)} seeds ({int((diff > 0).sum())} ahead)")


if __name__ == "__main__":
    main()
