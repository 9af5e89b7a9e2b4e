"""The lift b (rad) a sweep's policy commands along a course, averaged over 0.2 m bins of the base's distance (m).

    .venv/bin/python reports/experiments/sde/lift_profile.py data/sweeps/sde/sde-seed2/ppo [TERRAIN] [EPISODES]

Runs the policy deterministically on TERRAIN (default extra_blocks, faces at 1.0 and 2.0 m) with evaluate's episode
seeds (1000, 1001, ...) and prints, per episode, how it ended and b in each bin ("-": the base never got there).
"""

from __future__ import annotations

import sys

import numpy as np

import hexpipe
from hexpipe.envs.hexapod import HexapodEnv

BIN = 0.2  # m of base distance per column


def profile(policy_dir: str, terrain: str, episodes: int) -> None:
    policy = hexpipe.load_policy(policy_dir)
    env = HexapodEnv.from_params(policy.params, terrain, obs_sensors=policy.sensors)
    edges = np.arange(0.0, 3.0, BIN)
    print("episode end  distance  " + " ".join(f"{lo:4.1f}" for lo in edges))
    for episode in range(episodes):
        obs, info = env.reset(seed=1000 + episode)
        distance, lift, done = [], [], False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy.predict(obs))
            done = terminated or truncated
            distance.append(info["distance"])
            lift.append(float(obs["cpg"][1]))
        x, b = np.array(distance), np.array(lift)
        cells = [b[(x >= lo) & (x < lo + BIN)] for lo in edges]
        row = " ".join(f"{c.mean():.2f}" if c.size else "  - " for c in cells)
        print(f"{episode:7d} {info['termination']:5s} {x[-1]:8.2f}  {row}")
    env.close()


if __name__ == "__main__":
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    profile(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else "extra_blocks",
            int(sys.argv[3]) if len(sys.argv) > 3 else 3)
