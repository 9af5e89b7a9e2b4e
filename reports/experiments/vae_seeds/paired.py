"""`vae_seeds` six-split reading: the rise head's weight 8 minus weight 1 on the distance and height probes, paired by
vae.seed (the same held-out episodes), with a t interval over the seeds. Reads OUT/<name>-s<seed>-report/metrics.json
as `grid.sh` writes them.

Usage: python paired.py /tmp/vae_seeds --base fw1 --arm fw8 --seeds 0,1,2,3,4,5
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from scipy import stats


def probe(out: Path, name: str, seed: int) -> dict[str, float]:
    return json.loads((out / f"{name}-s{seed}-report" / "metrics.json").read_text())["probe"]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("out", type=Path)
    parser.add_argument("--base", default="fw1")
    parser.add_argument("--arm", default="fw8")
    parser.add_argument("--seeds", default="0,1,2,3,4,5")
    args = parser.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    for key in ("rise_distance_r2", "rise_height_r2"):
        base = np.array([probe(args.out, args.base, s)[key] for s in seeds])
        arm = np.array([probe(args.out, args.arm, s)[key] for s in seeds])
        diff = arm - base
        half = stats.t.ppf(0.975, len(seeds) - 1) * diff.std(ddof=1) / np.sqrt(len(seeds))
        arm_half = stats.t.ppf(0.975, len(seeds) - 1) * arm.std(ddof=1) / np.sqrt(len(seeds))
        print(f"{key}: per seed {args.base} " + " ".join(f"{v:.3f}" for v in base)
              + f"; {args.arm} " + " ".join(f"{v:.3f}" for v in arm))
        print(f"  {args.arm} mean {arm.mean():.3f} [{arm.mean() - arm_half:.3f}, {arm.mean() + arm_half:.3f}]; "
              f"{args.base} mean {base.mean():.3f}; {args.arm} minus {args.base} {diff.mean():+.3f} "
              f"[{diff.mean() - half:+.3f}, {diff.mean() + half:+.3f}] (95% t interval over {len(seeds)} seeds)")


if __name__ == "__main__":
    main()
