"""How often a training distribution's block courses open with a deep block, and how many blocks they hold.

    .venv/bin/python reports/experiments/deep_track/depth_stats.py varied_open \
        reports/experiments/deep_track/varied_open_deep.yaml

The height map reaches 1.4 m ahead, so as the lift begins (about 0.5 m before a face) a block 0.9 m deep or more
fills the map from its face on, as the suite's wide block (1.0 m) does. Draws 20000 courses per terrain at
difficulty 1 (the curriculum's top level) from one seeded generator; only block courses are counted.
"""

import sys

import numpy as np

from hexpipe.sim.terrain import TerrainError, load_terrain, realize

DRAWS = 20000
DEEP = 0.9  # m

for name in sys.argv[1:] or ["varied_open"]:
    try:
        recipe, rng = load_terrain(name), np.random.default_rng(0)
    except TerrainError as exc:
        sys.exit(f"error: {exc}")
    courses = first_deep = any_deep = blocks = 0
    for _ in range(DRAWS):
        boxes = sorted(realize(recipe, rng, 1.0).boxes, key=lambda b: b.center[0])
        if not boxes:
            continue  # a flat or rough episode
        depths = [b.size[0] for b in boxes]
        courses += 1
        first_deep += depths[0] >= DEEP
        any_deep += any(d >= DEEP for d in depths)
        blocks += len(boxes)
    if not courses:
        sys.exit(f"error: {name}: no block courses in {DRAWS} draws")
    print(f"{name}: {courses} block courses of {DRAWS}; first block >= {DEEP} m deep in {first_deep / courses:.3f}, "
          f"any in {any_deep / courses:.3f}; {blocks / courses:.2f} blocks a course")
