"""How the height map's reference moves with the body along a course, and what it does to a block's reading.

    .venv/bin/python reports/experiments/sde/map_reference.py data/sweeps/sde/sde-seed2/ppo [TERRAIN] [EPISODES]

The map reads terrain heights above the stance plane, the base's height minus `sim.body_height`, so a body raised
or lowered by the legs on a block shifts every cell. Runs the policy deterministically on TERRAIN (default
extra_blocks, two 0.10 m blocks with faces at 1.0 and 2.0 m) with evaluate's episode seeds (1000, 1001, ...) and
prints, per 0.2 m of the base's distance: the plane's offset from the ground under the base (m; 0 when the body
stands at its nominal height), the highest cell of the map's corridor from 0.34 to 1.4 m ahead of the base (m; a
0.10 m block in view reads 0.10 at offset 0), and the lift b the policy commands (rad).
"""

from __future__ import annotations

import sys

import numpy as np

import hexpipe
from hexpipe.envs.hexapod import HexapodEnv

BIN = 0.2  # m of base distance per row
AHEAD_ROWS = slice(15, None)  # rows of the default 32-row map from -0.6 to 1.4 m: 0.34 m ahead onwards
CORRIDOR = slice(12, 20)  # the central 8 of 32 columns: 0.4 m across, where the legs walk


def trace(policy_dir: str, terrain: str, episodes: int) -> None:
    policy = hexpipe.load_policy(policy_dir)
    env = HexapodEnv.from_params(policy.params, terrain, obs_sensors=policy.sensors)
    for episode in range(episodes):
        obs, info = env.reset(seed=1000 + episode)
        rows, done = [], False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy.predict(obs))
            done = terminated or truncated
            view = env.view()
            x, y = np.array([view.base_pos[0]]), np.array([view.base_pos[1]])
            offset = view.base_pos[2] - view.body_height - float(view.terrain.height_at(x, y)[0])
            ahead = float(env.sense(("heightmap",))["heightmap"][AHEAD_ROWS, CORRIDOR].max())
            rows.append((info["distance"], offset, ahead, float(obs["cpg"][1])))
        r = np.array(rows)
        print(f"episode {episode}: {info['termination']} at {r[-1, 0]:.2f} m")
        print("  base (m)  plane offset (m)  highest cell ahead (m)  b (rad)")
        for lo in np.arange(0.0, 3.0, BIN):
            cell = r[(r[:, 0] >= lo) & (r[:, 0] < lo + BIN)]
            if len(cell):
                print(f"  {lo:8.1f}  {cell[:, 1].mean():+16.3f}  {cell[:, 2].mean():22.3f}  {cell[:, 3].mean():7.2f}")
    env.close()


if __name__ == "__main__":
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    trace(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else "extra_blocks",
          int(sys.argv[3]) if len(sys.argv) > 3 else 3)
