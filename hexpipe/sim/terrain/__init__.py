"""Terrains for the hexapod course: one module per job, re-exported here (`from hexpipe.sim.terrain import ...`).

The robot starts at the origin and walks along +x towards a goal 3 m ahead; the ground is z = 0 (m).

* `model`: `Terrain` is concrete and fully realised (boxes and height fields, no randomness). It answers
  `height_at` in pure NumPy (the height-map sensor's source, so it must agree with what PyBullet
  collides with) and round-trips through `to_dict` (MCAP metadata).
* `primitives`: blocks, stairs, rough ground, random blocks and the `varied` training mix, as free functions.
* `recipes`: `TerrainRecipe` may hold random parts; `realize(recipe, rng)` turns it into a `Terrain`,
  deterministically given the generator state. `load_terrain` takes a scenario name (`SCENARIOS`) or a YAML path.
* `builder`: `build_terrain(terrain, client)` creates it in PyBullet (the only PyBullet code here).

YAML format (see terrains/*.yaml for commented examples; every section is optional)::

    name: my_course          # defaults to the file name without extension
    friction: 0.9            # lateral friction of every terrain body; default: the sim's setting
    boxes:                   # static boxes; each entry is one of the two forms below
      - {center: [1.15, 0.0, 0.05], size: [0.3, 2.0, 0.1], yaw: 0.0, rgba: [0.55, 0.35, 0.2, 1]}
      - {face: 2.0, depth: 0.3, height: 0.08, width: 2.0, y: 0.0}   # block across the path
    rough: {x: [0.4, 4.0], y: [-1.5, 1.5], cell: 0.05, amplitude: 0.035, smoothing: 0.1,
            ramp: 0.3, flat: 0.1}
    stairs: {start: 1.0, steps: 3, rise: 0.05, run: 0.35, top: 2.0, width: 2.0}
    random_blocks: {count: [1, 3], height: [0.06, 0.12], depth: [0.2, 1.0], face: [0.8, 2.6], gap: 0.4}
    varied: {difficulty: 1.0, blocks: 0.7, rough: 0.2, flat: 0.1, count: [1, 3], height: [0.04, 0.12],
             depth: [0.2, 1.0], face: [0.6, 2.6], gap: 0.4, amplitude: [0.015, 0.035]}

All lengths are metres, angles radians. `center` is the box centre and `size` its full extents;
`face` is the x of a block's near face, `depth` its extent along x, `width` across (centred on `y`).
A malformed file raises `TerrainError` with one line naming the file and the entry at fault.
"""

from hexpipe.sim.terrain.builder import build_terrain
from hexpipe.sim.terrain.model import Box, HeightField, Terrain, TerrainError
from hexpipe.sim.terrain.primitives import VARIANTS, block, random_blocks, rough_field, stairs, varied
from hexpipe.sim.terrain.recipes import (
    SCENARIOS,
    BlockSpec,
    BoxSpec,
    RandomBlocksSpec,
    RoughSpec,
    StairsSpec,
    TerrainRecipe,
    VariedSpec,
    load_terrain,
    parse_recipe,
    realize,
)

__all__ = [
    "SCENARIOS",
    "VARIANTS",
    "BlockSpec",
    "Box",
    "BoxSpec",
    "HeightField",
    "RandomBlocksSpec",
    "RoughSpec",
    "StairsSpec",
    "Terrain",
    "TerrainError",
    "TerrainRecipe",
    "VariedSpec",
    "block",
    "build_terrain",
    "load_terrain",
    "parse_recipe",
    "random_blocks",
    "realize",
    "rough_field",
    "stairs",
    "varied",
]
