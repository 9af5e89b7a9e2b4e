"""The lift b (rad) a sweep's policy commands along a course, averaged over 0.2 m bins of the base's distance (m).

    .venv/bin/python reports/experiments/sde/lift_profile.py data/sweeps/sde/sde-seed2/ppo [TERRAIN] [EPISODES]

Runs the policy deterministically on TERRAIN (default extra_blocks, faces at 1.0 and 2.0 m) with evaluate's episode
seeds (1000, 1001, ...) and prints, per episode, how it ended and b in each bin ("-": the base never got there).
"""

from __future__ import annotations

import numpy as np
from course import BIN, bins, episodes, main


def profile(policy_dir: str, terrain: str, count: int) -> None:
    print("episode end  distance  " + " ".join(f"{lo:4.1f}" for lo in np.arange(0.0, 3.0, BIN)))
    runs = episodes(policy_dir, terrain, count, lambda env, obs, info: (float(obs["cpg"][1]),))
    for episode, (end, rows) in enumerate(runs):
        row = " ".join(f"{cell[:, 1].mean():.2f}" if len(cell) else "  - " for _, cell in bins(rows))
        print(f"{episode:7d} {end:5s} {rows[-1, 0]:8.2f}  {row}")


if __name__ == "__main__":
    main(profile, __doc__)
