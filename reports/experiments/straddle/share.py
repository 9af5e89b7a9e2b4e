"""How often a training distribution holds a two-block straddle: a gap of 0.5-1.0 m between two consecutive blocks
both at least 8 cm high, over 4000 draws (seeds 0-3999) of `varied` at full difficulty with the given weights.

    .venv/bin/python reports/experiments/straddle/share.py
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np

from hexpipe.sim.terrain import load_terrain
from hexpipe.sim.terrain.primitives import varied

DRAWS = 4000


def straddle_share(weights: tuple[float, float, float], **ranges) -> tuple[float, float]:
    """(share of block episodes, share of all episodes) that hold a straddle."""
    blocks = straddles = 0
    for seed in range(DRAWS):
        variant, boxes, _ = varied(np.random.default_rng(seed), 1.0, weights, **ranges)
        if variant != "blocks":
            continue
        blocks += 1
        b = sorted(boxes, key=lambda box: box.center[0])
        for near, far in itertools.pairwise(b):
            gap = (far.center[0] - far.size[0] / 2) - (near.center[0] + near.size[0] / 2)
            if 0.5 <= gap <= 1.0 and min(near.size[2], far.size[2]) >= 0.08:
                straddles += 1
                break
    return straddles / blocks, straddles / DRAWS


if __name__ == "__main__":
    for name in ("varied_open", str(Path(__file__).resolve().parent / "pairs_open.yaml")):
        v = load_terrain(name).varied
        of_blocks, of_all = straddle_share((v.blocks, v.rough, v.flat), count=v.count, height=v.height,
                                           depth=v.depth, face=v.face, gap=v.gap)
        print(f"{Path(name).name}: {of_blocks:.3f} of block episodes, {of_all:.3f} of all episodes")
