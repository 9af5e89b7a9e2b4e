"""Terrain primitives: small free functions that make boxes and height fields from their dimensions (m).

The random ones (`rough_field`, `random_blocks`, `varied`) draw only from the generator they are given, so a
terrain is deterministic given its seed.
"""

from __future__ import annotations

import math

import numpy as np

from hexpipe.sim.terrain.model import BROWN, Box, HeightField, Rgba, Vec2

MAX_RANDOM_TRIES = 64  # random_blocks: depth draws per block count before trying one block fewer


def block(
    face_x: float, depth: float, height: float, width: float = 2.0, y: float = 0.0, rgba: Rgba = BROWN
) -> Box:
    """A block across the path: near face at `face_x`, `depth` along x, `width` centred on `y` (m)."""
    return Box(center=(face_x + depth / 2, y, height / 2), size=(depth, width, height), rgba=rgba)


def stairs(
    start: float,
    steps: int = 3,
    rise: float = 0.05,
    run: float = 0.35,
    top: float = 2.0,
    width: float = 2.0,
    rgba: Rgba = BROWN,
) -> tuple[Box, ...]:
    """`steps` risers of `rise` each, `run` apart, the first at x = `start`; the last tread is the flat
    top, `top` long (m). One box per tread, side by side (no overlap), each as high as its tread.
    """
    boxes = []
    for k in range(steps):
        depth = top if k == steps - 1 else run
        boxes.append(block(start + k * run, depth, (k + 1) * rise, width=width, rgba=rgba))
    return tuple(boxes)


def _smooth_noise(rng: np.random.Generator, shape: tuple[int, int], sigma: float) -> np.ndarray:
    """White noise blurred by a separable Gaussian of `sigma` cells, normalised to unit std."""
    r = max(1, math.ceil(3 * sigma))
    kernel = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    kernel /= kernel.sum()
    nx, ny = shape
    noise = rng.standard_normal((nx + 2 * r, ny + 2 * r))  # drawn with a margin: no edge artefacts
    noise = sum(w * noise[t : t + nx, :] for t, w in enumerate(kernel))
    noise = sum(w * noise[:, t : t + ny] for t, w in enumerate(kernel))
    return noise / max(float(noise.std()), 1e-12)


def rough_field(
    rng: np.random.Generator,
    x: Vec2 = (0.4, 4.0),
    y: Vec2 = (-1.5, 1.5),
    cell: float = 0.05,
    amplitude: float = 0.035,
    smoothing: float = 0.1,
    ramp: float = 0.3,
    flat: float = 0.1,
) -> HeightField:
    """Smooth random bumps over x in `x`, y in `y` (m), nodes every `cell` (m).

    Heights are amplitude * (1 + tanh(0.75 n)) for unit-std Gaussian-filtered noise n (correlation length
    `smoothing`, m): undulations of about +-amplitude around a level of amplitude, bounded in [0, 2
    amplitude]. They stay >= 0 because the ground plane at z = 0 would hide anything lower. A strip `flat`
    (m) wide along every edge is exactly 0, then heights ease in smoothly over `ramp` (m): the field starts
    flat (the robot never spawns inside it) and has no cliff at its borders (edge nodes are always 0).
    """
    nx = round((x[1] - x[0]) / cell) + 1
    ny = round((y[1] - y[0]) / cell) + 1
    n = _smooth_noise(rng, (nx, ny), smoothing / cell)
    heights = amplitude * (1.0 + np.tanh(0.75 * n))

    def window(count: int) -> np.ndarray:
        edge = np.minimum(np.arange(count), np.arange(count)[::-1]) * cell  # distance to the nearest edge (m)
        if ramp <= 0:
            return (edge > flat).astype(np.float64)
        t = np.clip((edge - flat) / ramp, 0.0, 1.0)
        return t * t * (3 - 2 * t)  # smoothstep: flat at both ends

    heights *= window(nx)[:, None] * window(ny)[None, :]
    return HeightField(origin=(x[0], y[0]), cell=cell, heights=heights)


def random_blocks(
    rng: np.random.Generator,
    count: tuple[int, int] = (1, 3),
    height: Vec2 = (0.06, 0.12),
    depth: Vec2 = (0.2, 1.0),
    face: Vec2 = (0.8, 2.6),
    gap: float = 0.4,
    width: float = 2.0,
) -> tuple[Box, ...]:
    """Domain-randomised blocks across the path, sorted along x, at least `gap` (m) apart.

    count, height, depth and face positions are uniform in their [low, high] ranges (m). Given the
    depths, the faces are uniform over every placement that fits in `face` with the gaps; if the drawn
    depths cannot fit (many long blocks), depths are redrawn, and after 64 tries one block fewer is used.
    """
    n = int(rng.integers(count[0], count[1] + 1))
    span = face[1] - face[0]
    if depth[0] + gap > 0:  # no more blocks than fit at their shortest: keeps the loop below short
        n = min(n, 1 + math.floor(max(span, 0.0) / (depth[0] + gap)))
    while n > 0:
        for _ in range(MAX_RANDOM_TRIES):
            depths = rng.uniform(depth[0], depth[1], n)
            slack = span - float(depths[:-1].sum()) - gap * (n - 1)  # free room for the faces
            if slack >= 0:
                break
        else:
            n -= 1
            continue
        heights = rng.uniform(height[0], height[1], n)
        cuts = np.sort(rng.uniform(0.0, slack, n))
        offsets = np.concatenate(([0.0], np.cumsum(depths[:-1] + gap)))
        faces = face[0] + cuts + offsets
        return tuple(block(f, d, h, width=width) for f, d, h in zip(faces, depths, heights, strict=True))
    return ()


VARIANTS = ("blocks", "rough", "flat")  # the kinds of episode a `varied` terrain draws from


def _lerp(lo: float, hi: float, t: float) -> float:
    return lo + (hi - lo) * t


def varied(
    rng: np.random.Generator,
    difficulty: float = 1.0,
    weights: tuple[float, float, float] = (0.7, 0.2, 0.1),
    count: tuple[int, int] = (1, 3),
    height: Vec2 = (0.04, 0.12),
    depth: Vec2 = (0.2, 1.0),
    face: Vec2 = (0.6, 2.6),
    gap: float = 0.4,
    amplitude: Vec2 = (0.015, 0.035),
    width: float = 2.0,
) -> tuple[str, tuple[Box, ...], tuple[HeightField, ...]]:
    """A training episode: (variant, boxes, height fields), the variant drawn from VARIANTS by `weights`.

    `difficulty` in [0, 1] (legged_gym style) sets how far up their ranges the hard parts reach: block heights are
    uniform in [height low, lerp(height, difficulty)], counts in [count low, round(lerp(count, difficulty))], and
    the bumps' amplitude is lerp(amplitude, difficulty). At 0: one block of the lowest height, or the gentlest
    bumps; at 1: `random_blocks` over the whole ranges. Depths and face positions are drawn over their whole
    ranges at every difficulty: they vary what the robot sees, not how hard it is to cross.
    """
    p = np.asarray(weights, dtype=float)
    variant = VARIANTS[int(rng.choice(len(VARIANTS), p=p / p.sum()))]
    if variant == "blocks":
        top_count = round(_lerp(count[0], count[1], difficulty))
        top_height = _lerp(height[0], height[1], difficulty)
        boxes = random_blocks(rng, (count[0], top_count), (height[0], top_height), depth, face, gap, width)
        return variant, boxes, ()
    if variant == "rough":
        return variant, (), (rough_field(rng, amplitude=_lerp(amplitude[0], amplitude[1], difficulty)),)
    return variant, (), ()
