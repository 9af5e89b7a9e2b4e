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

import numpy as np
from course import bins, episodes, main

AHEAD_ROWS = slice(15, None)  # rows of the default 32-row map from -0.6 to 1.4 m: 0.34 m ahead onwards
CORRIDOR = slice(12, 20)  # the central 8 of 32 columns: 0.4 m across, where the legs walk


def reference(env, obs: dict, info: dict) -> tuple[float, float, float]:
    """The plane's offset from the ground under the base (m), the highest corridor cell ahead (m), b (rad)."""
    view = env.view()
    x, y = np.array([view.base_pos[0]]), np.array([view.base_pos[1]])
    offset = view.base_pos[2] - view.body_height - float(view.terrain.height_at(x, y)[0])
    ahead = float(env.sense(("heightmap",))["heightmap"][AHEAD_ROWS, CORRIDOR].max())
    return offset, ahead, float(obs["cpg"][1])


def trace(policy_dir: str, terrain: str, count: int) -> None:
    for episode, (end, rows) in enumerate(episodes(policy_dir, terrain, count, reference)):
        print(f"episode {episode}: {end} at {rows[-1, 0]:.2f} m")
        print("  base (m)  plane offset (m)  highest cell ahead (m)  b (rad)")
        for lo, cell in bins(rows):
            if len(cell):
                print(f"  {lo:8.1f}  {cell[:, 1].mean():+16.3f}  {cell[:, 2].mean():22.3f}  {cell[:, 3].mean():7.2f}")


if __name__ == "__main__":
    main(trace, __doc__)
