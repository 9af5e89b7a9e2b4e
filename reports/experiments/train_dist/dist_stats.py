"""How often a training distribution draws the suite's hard cases: a block of 0.10 m or more, and two blocks at
least 0.09 m high whose faces lie 0.8-1.2 m apart (extra_blocks' faces lie 1.0 m apart, the robot's length).

    .venv/bin/python reports/experiments/train_dist/dist_stats.py varied reports/experiments/train_dist/*.yaml

Draws 20000 courses per terrain at difficulty 1 (the curriculum's top level) from one seeded generator.
"""

import sys

import numpy as np

from hexpipe.sim.terrain import load_terrain, realize

DRAWS = 20000

for name in sys.argv[1:] or ["varied"]:
    recipe, rng = load_terrain(name), np.random.default_rng(0)
    tall = pair = tall_pair = 0
    for _ in range(DRAWS):
        boxes = sorted(realize(recipe, rng, 1.0).boxes, key=lambda b: b.center[0])
        heights = [b.size[2] for b in boxes]
        faces = [b.center[0] - b.size[0] / 2 for b in boxes]
        gaps = [(faces[i + 1] - faces[i], min(heights[i], heights[i + 1])) for i in range(len(boxes) - 1)]
        tall += any(h >= 0.10 for h in heights)
        pair += any(0.8 <= g <= 1.2 for g, _ in gaps)
        tall_pair += any(0.8 <= g <= 1.2 and h >= 0.09 for g, h in gaps)
    print(f"{name}: a block >= 0.10 m in {tall / DRAWS:.3f} of courses; faces 0.8-1.2 m apart {pair / DRAWS:.3f}, "
          f"both >= 0.09 m high {tall_pair / DRAWS:.3f}")
