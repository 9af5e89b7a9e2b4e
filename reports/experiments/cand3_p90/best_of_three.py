"""`cand3_p90` in reports/experiments/README.md: had best-of-three picked among a sweep's five draws, how many terrains
would the kept draw be beaten outright on? Reads each trial's validation return (reports/sweeps/NAME/*/ppo/
selection.json: one candidate per trial, 60 episodes of the training terrains) and its count of terrains beaten
outright by a fixed gait (the `seed N: K` lines of a `head150/dominance.py` printout, the arm named by --arm).
Prints every draw, then each of the C(5, 3) triples with the draw the highest return keeps.

Usage: python best_of_three.py reports/sweeps/price90_p138 reports/experiments/price90_p138/dominance.txt --arm 2
(--arm: which block of `seed N: K` lines in the printout, 1 for the first arm, 2 for the second.)
"""

from __future__ import annotations

import argparse
import itertools
import json
import re
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("sweep", type=Path)
    parser.add_argument("dominance", type=Path)
    parser.add_argument("--arm", type=int, default=2)
    args = parser.parse_args()
    returns = {}
    for path in sorted(args.sweep.glob("*/ppo/selection.json")):
        chosen = json.loads(path.read_text())
        returns[int(chosen["chosen_seed"])] = chosen["candidates"][str(chosen["chosen_seed"])]["return"]
    blocks: list[dict[int, int]] = []
    for line in args.dominance.read_text().splitlines():
        match = re.match(r"\s*seed\s+(\d+):\s+(\d+)", line)
        if not match:
            continue
        seed, count = int(match[1]), int(match[2])
        if not blocks or seed in blocks[-1]:
            blocks.append({})
        blocks[-1][seed] = count
    beaten = blocks[args.arm - 1]
    seeds = sorted(set(returns) & set(beaten))
    print("seed  validation return  beaten outright")
    for seed in seeds:
        print(f"{seed:4d}  {returns[seed]:17.1f}  {beaten[seed]:15d}")
    kept_counts = []
    print("\ntriple      kept  beaten")
    for triple in itertools.combinations(seeds, 3):
        kept = max(triple, key=lambda s: returns[s])
        kept_counts.append(beaten[kept])
        print(f"{','.join(map(str, triple)):10s}  {kept:4d}  {beaten[kept]:6d}")
    n = len(kept_counts)
    print(f"\none draw: mean {sum(beaten[s] for s in seeds) / len(seeds):.2f}, at most 3 in "
          f"{sum(beaten[s] <= 3 for s in seeds)} of {len(seeds)}")
    print(f"best of three: mean {sum(kept_counts) / n:.2f}, at most 3 in {sum(c <= 3 for c in kept_counts)} of {n}")


if __name__ == "__main__":
    main()
