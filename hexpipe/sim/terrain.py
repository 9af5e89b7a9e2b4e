"""Terrains for the hexapod course: data model, named scenarios, YAML recipes, PyBullet builder.

The robot starts at the origin and walks along +x towards a goal 3 m ahead; the ground is z = 0 (m).

Two layers:

* `Terrain` is concrete and fully realised (boxes and height fields, no randomness). It answers
  `height_at` in pure NumPy (the height-map sensor's source, so it must agree with what PyBullet
  collides with), builds itself in a PyBullet client, and round-trips through `to_dict` (MCAP metadata).
* `TerrainRecipe` may hold random parts; `realize(recipe, rng)` turns it into a `Terrain`,
  deterministically given the generator state. `load_terrain` takes a scenario name or a YAML path.

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

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    ValidationError,
    model_validator,
)

from hexpipe.validation import format_validation_error, read_yaml, show

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]
Rgba = tuple[float, float, float, float]

BROWN: Rgba = (0.55, 0.35, 0.2, 1.0)  # blocks and steps
SOIL: Rgba = (0.45, 0.4, 0.3, 1.0)  # height fields
GREY: Rgba = (0.6, 0.6, 0.6, 1.0)  # ground plane
GROUND_HALF_EXTENT = 20.0  # the ground plane is a 40 m x 40 m static box centred on the origin (m)
GROUND_THICKNESS = 0.1  # (m); its top is z = 0
# Bounds on what a terrain file may ask for, so that a typo gives an error instead of a hang or an OOM kill.
MAX_GRID_NODES = 250_000  # height-field nodes: PyBullet builds 1M nodes in ~6 s, 4M in ~40 s (at every reset)
MAX_NOISE_WORK = 200_000_000  # rough: padded noise nodes x Gaussian kernel taps (~1 s of NumPy, ~32 MB)
MAX_BOXES = 200  # boxes of one terrain, all parts together: each step's height map tests every box
MAX_VALUE = 1000.0  # every number of a terrain file (m, rad or friction) within +-this: PyBullet needs sane sizes
MAX_RANDOM_TRIES = 64  # random_blocks: depth draws per block count before trying one block fewer


class TerrainError(ValueError):
    """A bad terrain file, name or definition; the message is one line naming the entry at fault."""


# ----------------------------------------------------------------------------------------------------------
# Concrete terrain
# ----------------------------------------------------------------------------------------------------------


def _floats(value: Any, n: int, what: str) -> tuple[float, ...]:
    out = tuple(float(v) for v in value)
    if len(out) != n or not all(math.isfinite(v) for v in out):
        raise TerrainError(f"{what}: expected {n} finite numbers, got {list(value)}")
    return out


@dataclass(frozen=True)
class Box:
    """A static box: `center` (m), full `size` extents (m), `yaw` about +z (rad), colour `rgba`."""

    center: Vec3
    size: Vec3
    yaw: float = 0.0
    rgba: Rgba = BROWN

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _floats(self.center, 3, "Box.center"))
        object.__setattr__(self, "size", _floats(self.size, 3, "Box.size"))
        object.__setattr__(self, "yaw", float(self.yaw))
        object.__setattr__(self, "rgba", _floats(self.rgba, 4, "Box.rgba"))
        if min(self.size) <= 0:
            raise TerrainError(f"Box.size: expected 3 positive numbers, got {list(self.size)}")

    @property
    def top(self) -> float:
        """Height of the top face (m)."""
        return self.center[2] + 0.5 * self.size[2]


@dataclass(frozen=True, eq=False)
class HeightField:
    """A height field: node [i, j] lies at (x0 + i*cell, y0 + j*cell) with height heights[i, j] (m).

    Row index i runs along +x, column j along +y. Between nodes the surface is the two triangles PyBullet
    uses: each cell is split along the diagonal from node (i+1, j) to node (i, j+1).
    """

    origin: Vec2  # world (x, y) of node [0, 0] (m)
    cell: float  # node spacing along both axes (m)
    heights: np.ndarray  # (nx, ny) float64, read-only (m)
    rgba: Rgba = SOIL

    def __post_init__(self) -> None:
        object.__setattr__(self, "origin", _floats(self.origin, 2, "HeightField.origin"))
        object.__setattr__(self, "cell", float(self.cell))
        object.__setattr__(self, "rgba", _floats(self.rgba, 4, "HeightField.rgba"))
        heights = np.array(self.heights, dtype=np.float64)  # a private copy, so freezing it is safe
        if heights.ndim != 2 or min(heights.shape) < 2:
            raise TerrainError(
                f"HeightField.heights: expected a 2-D grid of at least 2x2, got {heights.shape}"
            )
        if not np.isfinite(heights).all():
            raise TerrainError("HeightField.heights: contains non-finite values")
        if not (math.isfinite(self.cell) and self.cell > 0):
            raise TerrainError(f"HeightField.cell: expected a positive number, got {self.cell}")
        heights.setflags(write=False)
        object.__setattr__(self, "heights", heights)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, HeightField):
            return NotImplemented
        return (
            self.origin == other.origin
            and self.cell == other.cell
            and self.rgba == other.rgba
            and np.array_equal(self.heights, other.heights)
        )

    def __hash__(self) -> int:
        return hash((self.origin, self.cell, self.rgba, self.heights.shape, self.heights.tobytes()))

    @property
    def extent(self) -> tuple[Vec2, Vec2]:
        """((x_min, x_max), (y_min, y_max)) covered by the nodes (m)."""
        nx, ny = self.heights.shape
        x0, y0 = self.origin
        return (x0, x0 + (nx - 1) * self.cell), (y0, y0 + (ny - 1) * self.cell)

    def height_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Surface height (m) at 1-D world point arrays (m); 0 outside the field (no contribution above
        the ground plane). Tuned for ~1000 points: every NumPy call here costs microseconds."""
        nx, ny = self.heights.shape
        u = (x - self.origin[0]) * (1.0 / self.cell)
        v = (y - self.origin[1]) * (1.0 / self.cell)
        uc = np.minimum(np.maximum(u, 0.0), nx - 1.0)
        vc = np.minimum(np.maximum(v, 0.0), ny - 1.0)
        inside = (uc == u) & (vc == v)
        i = np.minimum(uc.astype(np.intp), nx - 2)
        j = np.minimum(vc.astype(np.intp), ny - 2)
        fu = uc - i
        fv = vc - j
        k = i * ny + j
        flat = self.heights.ravel()
        h00, h10, h01, h11 = flat[k], flat[k + ny], flat[k + 1], flat[k + ny + 1]
        # Plane of the triangle (i, j), (i+1, j), (i, j+1), plus a correction that is zero on the
        # diagonal and bends the surface onto the triangle (i+1, j), (i, j+1), (i+1, j+1) beyond it.
        beyond = np.maximum(fu + fv - 1.0, 0.0)
        z = h00 + fu * (h10 - h00) + fv * (h01 - h00) + beyond * (h11 - h10 - h01 + h00)
        z *= inside
        return z


@dataclass(frozen=True)
class Terrain:
    """A concrete terrain: the ground plane (z = 0), static boxes and height fields, optional friction."""

    name: str
    boxes: tuple[Box, ...] = ()
    heightfields: tuple[HeightField, ...] = ()
    friction: float | None = None  # lateral friction for every terrain body; None keeps the caller's default

    def __post_init__(self) -> None:
        object.__setattr__(self, "boxes", tuple(self.boxes))
        object.__setattr__(self, "heightfields", tuple(self.heightfields))
        if self.friction is not None:
            object.__setattr__(self, "friction", float(self.friction))
            if not self.friction > 0:
                raise TerrainError(f"Terrain.friction: expected a positive number, got {self.friction}")

    @cached_property
    def _box_table(self) -> tuple[np.ndarray, ...] | None:
        """Per-box arrays (cx, cy, cos, sin, half_x, half_y, top), shape (B, 1), for broadcasting."""
        if not self.boxes:
            return None
        rows = np.array(
            [
                (*b.center[:2], math.cos(b.yaw), math.sin(b.yaw), b.size[0] / 2, b.size[1] / 2, b.top)
                for b in self.boxes
            ]
        )
        return tuple(col[:, None] for col in rows.T)

    @cached_property
    def _any_yaw(self) -> bool:
        return any(b.yaw != 0.0 for b in self.boxes)

    def height_at(self, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray:
        """Terrain top height (m) at world points (m), any broadcastable shapes; pure NumPy.

        The max of the ground (0), every box top whose footprint holds the point (edges included) and
        every height field covering the point, interpolated on PyBullet's triangles. This is what a ray
        cast straight down hits, so the height map agrees with the physics.
        """
        x, y = np.broadcast_arrays(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))
        shape = x.shape
        xf, yf = x.reshape(-1), y.reshape(-1)
        out = np.zeros(xf.shape)
        if self._box_table is not None:  # all boxes at once, laid out (box, point)
            cx, cy, c, s, hx, hy, top = self._box_table
            dx = xf - cx
            dy = yf - cy
            if self._any_yaw:  # rotate into each box's frame
                dx, dy = c * dx + s * dy, c * dy - s * dx
            inside = np.abs(dx, out=dx) <= hx
            inside &= np.abs(dy, out=dy) <= hy
            tops = inside * top  # 0 outside a footprint, which the ground covers anyway
            np.maximum(out, tops[0] if len(tops) == 1 else tops.max(axis=0), out=out)
        for hf in self.heightfields:
            np.maximum(out, hf.height_at(xf, yf), out=out)
        return out.reshape(shape)

    def obstacle_distance(
        self, x: float, y: float, yaw: float, threshold: float = 0.03, max_range: float = 3.0
    ) -> float:
        """Distance (m) along heading `yaw` (rad) from (x, y) to where the terrain first rises more than
        `threshold` (m) above the height under (x, y); inf if it does not within `max_range` (m).

        Used to label data ("block ahead within 1 m"). Two vectorised passes: every 5 mm, then every
        0.1 mm inside the first 5 mm step that rises, so a spike narrower than 5 mm can be missed.
        """
        base = float(self.height_at(x, y)) + threshold
        c, s = math.cos(yaw), math.sin(yaw)

        def first_rise(d: np.ndarray) -> int | None:
            above = np.flatnonzero(self.height_at(x + d * c, y + d * s) > base)
            return int(above[0]) if above.size else None

        coarse = np.minimum(np.arange(1, math.ceil(max_range / 0.005) + 1) * 0.005, max_range)
        k = first_rise(coarse)
        if k is None:
            return math.inf
        lo = float(coarse[k - 1]) if k > 0 else 0.0
        fine = np.linspace(lo, float(coarse[k]), 51)[1:]
        return float(fine[first_rise(fine) or 0])

    def rise_ahead(
        self, x: float, y: float, yaw: float, max_range: float, threshold: float = 0.03, span: float = 0.1
    ) -> tuple[float, float]:
        """(distance, height) of the first rise ahead: where the terrain along heading `yaw` (rad) from (x, y)
        first climbs more than `threshold` above the height under (x, y) (as `obstacle_distance`), and how high it
        climbs (m above the height under (x, y)) within `span` m past that point, the footprint of a foot that
        lands on it. A block's height for a block, one riser for stairs. (inf, nan) if nothing rises within
        `max_range` (m). Labels for the VAE probes; pure NumPy.
        """
        distance = self.obstacle_distance(x, y, yaw, threshold=threshold, max_range=max_range)
        if not math.isfinite(distance):
            return math.inf, math.nan
        d = distance + np.linspace(0.0, span, 21)
        c, s = math.cos(yaw), math.sin(yaw)
        top = float(self.height_at(x + d * c, y + d * s).max())
        return distance, top - float(self.height_at(x, y))

    def build(self, client: int) -> list[int]:
        """Create the terrain as static bodies in PyBullet client `client`; returns their body ids.

        The ground is a thin 40 m x 40 m grey box with its top at z = 0. Height fields are placed with
        PyBullet's convention in mind: the shape is centred on its grid midpoint in x and y and on the
        midpoint of its min and max height in z, and the flat data is x-fastest (Fortran order).
        """
        import pybullet as p

        ids: list[int] = []

        def add_box(
            center: Sequence[float], half: Sequence[float], yaw: float, rgba: Sequence[float]
        ) -> None:
            col = p.createCollisionShape(p.GEOM_BOX, halfExtents=list(half), physicsClientId=client)
            vis = p.createVisualShape(
                p.GEOM_BOX, halfExtents=list(half), rgbaColor=list(rgba), physicsClientId=client
            )
            ids.append(
                p.createMultiBody(
                    baseMass=0,
                    baseCollisionShapeIndex=col,
                    baseVisualShapeIndex=vis,
                    basePosition=list(center),
                    baseOrientation=p.getQuaternionFromEuler([0.0, 0.0, yaw]),
                    physicsClientId=client,
                )
            )

        g = GROUND_HALF_EXTENT
        add_box((0.0, 0.0, -GROUND_THICKNESS / 2), (g, g, GROUND_THICKNESS / 2), 0.0, GREY)
        for b in self.boxes:
            add_box(b.center, [s / 2 for s in b.size], b.yaw, b.rgba)
        for hf in self.heightfields:
            nx, ny = hf.heights.shape
            lo, hi = float(hf.heights.min()), float(hf.heights.max())
            col = p.createCollisionShape(
                p.GEOM_HEIGHTFIELD,
                meshScale=[hf.cell, hf.cell, 1.0],
                heightfieldData=hf.heights.ravel(order="F").tolist(),
                numHeightfieldRows=nx,
                numHeightfieldColumns=ny,
                physicsClientId=client,
            )
            (x0, x1), (y0, y1) = hf.extent
            body = p.createMultiBody(
                baseMass=0,
                baseCollisionShapeIndex=col,
                basePosition=[(x0 + x1) / 2, (y0 + y1) / 2, (lo + hi) / 2],
                physicsClientId=client,
            )
            # No visual shape: PyBullet draws the collision mesh (also in TinyRenderer); just colour it.
            p.changeVisualShape(body, -1, rgbaColor=list(hf.rgba), physicsClientId=client)
            ids.append(body)
        if self.friction is not None:
            for body in ids:
                p.changeDynamics(body, -1, lateralFriction=self.friction, physicsClientId=client)
        return ids

    def to_dict(self) -> dict[str, Any]:
        """A JSON-serialisable description (heights as nested lists); inverse of `from_dict`."""
        return {
            "name": self.name,
            "friction": self.friction,
            "boxes": [
                {"center": list(b.center), "size": list(b.size), "yaw": b.yaw, "rgba": list(b.rgba)}
                for b in self.boxes
            ],
            "heightfields": [
                {
                    "origin": list(h.origin),
                    "cell": h.cell,
                    "heights": h.heights.tolist(),
                    "rgba": list(h.rgba),
                }
                for h in self.heightfields
            ],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Terrain:
        """Rebuild a terrain from `to_dict` output; raises TerrainError on malformed input."""
        try:
            return cls(
                name=str(data["name"]),
                friction=data.get("friction"),
                boxes=tuple(Box(**b) for b in data.get("boxes", ())),
                heightfields=tuple(
                    HeightField(**{**h, "heights": np.asarray(h["heights"], dtype=np.float64)})
                    for h in data.get("heightfields", ())
                ),
            )
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, TerrainError):
                raise
            raise TerrainError(f"terrain dict: {exc.__class__.__name__}: {exc}") from None


# ----------------------------------------------------------------------------------------------------------
# Primitives (small free functions, parameterised by their dimensions)
# ----------------------------------------------------------------------------------------------------------


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


# ----------------------------------------------------------------------------------------------------------
# Recipes (validated; what YAML files and scenario names turn into)
# ----------------------------------------------------------------------------------------------------------


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) and abs(v) <= MAX_VALUE


def _numbers(n: int, positive: bool = False, unit: bool = False) -> BeforeValidator:
    kind = "positive numbers" if positive else "numbers in [0, 1]" if unit else "numbers"
    kind += f" (|x| <= {MAX_VALUE:g})" if not unit else ""

    def check(value: Any) -> tuple[float, ...]:
        ok = isinstance(value, list | tuple) and len(value) == n and all(_is_number(v) for v in value)
        if ok and positive:
            ok = all(v > 0 for v in value)
        if ok and unit:
            ok = all(0 <= v <= 1 for v in value)
        if not ok:
            raise ValueError(f"expected {n} {kind}, got {show(value)}")
        return tuple(float(v) for v in value)

    return BeforeValidator(check)


def _range(
    integer: bool = False, positive: bool = False, strict: bool = False, upper: float = math.inf
) -> BeforeValidator:
    kind = "integers >= 0" if integer else "positive numbers" if positive else "numbers"
    kind += f" <= {upper:g}" if upper < math.inf else f" (|x| <= {MAX_VALUE:g})"
    order = "<" if strict else "<="

    def check(value: Any) -> tuple[float, float] | tuple[int, int]:
        ok = isinstance(value, list | tuple) and len(value) == 2 and all(_is_number(v) for v in value)
        if ok and integer:
            ok = all(isinstance(v, int) and v >= 0 for v in value)
        if ok:
            ok = all(v <= upper for v in value)
        if ok and positive:
            ok = all(v > 0 for v in value)
        if ok:
            ok = value[0] < value[1] if strict else value[0] <= value[1]
        if not ok:
            raise ValueError(f"expected [low, high] of {kind} with low {order} high, got {show(value)}")
        return (int(value[0]), int(value[1])) if integer else (float(value[0]), float(value[1]))

    return BeforeValidator(check)


# Strict scalars: YAML strings such as "0.1" or booleans are errors, ints are fine where floats are expected.
Num = Annotated[float, Field(strict=True, ge=-MAX_VALUE, le=MAX_VALUE, allow_inf_nan=False)]
Pos = Annotated[float, Field(strict=True, gt=0, le=MAX_VALUE, allow_inf_nan=False)]
NonNeg = Annotated[float, Field(strict=True, ge=0, le=MAX_VALUE, allow_inf_nan=False)]


class _Spec(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class BoxSpec(_Spec):
    """A box given by its centre and full size (m), yaw (rad)."""

    center: Annotated[Vec3, _numbers(3)]
    size: Annotated[Vec3, _numbers(3, positive=True)]
    yaw: Num = 0.0
    rgba: Annotated[Rgba, _numbers(4, unit=True)] = BROWN


class BlockSpec(_Spec):
    """Shorthand for a block across the path: near face x, depth along x, height, width across (m)."""

    face: Num
    depth: Pos
    height: Pos
    width: Pos = 2.0
    y: Num = 0.0
    rgba: Annotated[Rgba, _numbers(4, unit=True)] = BROWN


class RoughSpec(_Spec):
    """Smooth random bumps; see `rough_field`."""

    x: Annotated[Vec2, _range(strict=True)] = (0.4, 4.0)
    y: Annotated[Vec2, _range(strict=True)] = (-1.5, 1.5)
    cell: Pos = 0.05
    amplitude: NonNeg = 0.035
    smoothing: Pos = 0.1
    ramp: NonNeg = 0.3
    flat: NonNeg = 0.1

    @model_validator(mode="after")
    def _grid_size(self) -> RoughSpec:
        nx = round((self.x[1] - self.x[0]) / self.cell) + 1
        ny = round((self.y[1] - self.y[0]) / self.cell) + 1
        if min(nx, ny) < 2:
            raise ValueError(f"cell {self.cell} is larger than the field; need at least 2 nodes per axis")
        if nx * ny > MAX_GRID_NODES:
            raise ValueError(
                f"cell {self.cell} gives {nx}x{ny} nodes; at most {MAX_GRID_NODES} allowed (raise cell or shrink x, y)"
            )
        r = max(1, math.ceil(3 * self.smoothing / self.cell))  # the noise kernel's radius in cells (_smooth_noise)
        work = (nx + 2 * r) * (ny + 2 * r) * (2 * r + 1)
        if work > MAX_NOISE_WORK:
            raise ValueError(
                f"smoothing {self.smoothing} m is {self.smoothing / self.cell:.0f} cells of {self.cell} m: the noise "
                f"filter would need {work:.2g} operations (at most {MAX_NOISE_WORK:.0e}); lower smoothing or raise cell"
            )
        return self


class StairsSpec(_Spec):
    """Steps up; see `stairs`."""

    start: Num = 1.0
    steps: Annotated[int, Field(strict=True, ge=1, le=100)] = 3
    rise: Pos = 0.05
    run: Pos = 0.35
    top: Pos = 2.0
    width: Pos = 2.0


class RandomBlocksSpec(_Spec):
    """Domain randomisation; see `random_blocks`."""

    count: Annotated[tuple[int, int], _range(integer=True, upper=MAX_BOXES)] = (1, 3)
    height: Annotated[Vec2, _range(positive=True)] = (0.06, 0.12)
    depth: Annotated[Vec2, _range(positive=True)] = (0.2, 1.0)
    face: Annotated[Vec2, _range()] = (0.8, 2.6)
    gap: NonNeg = 0.4
    width: Pos = 2.0


class VariedSpec(_Spec):
    """A training distribution with a difficulty; see `varied`. Weights pick the episode's variant."""

    difficulty: Annotated[float, Field(strict=True, ge=0, le=1, allow_inf_nan=False)] = 1.0
    blocks: NonNeg = 0.7  # weight of block episodes
    rough: NonNeg = 0.2  # weight of rough-ground episodes
    flat: NonNeg = 0.1  # weight of flat episodes
    count: Annotated[tuple[int, int], _range(integer=True)] = (1, 3)
    height: Annotated[Vec2, _range(positive=True)] = (0.04, 0.12)
    depth: Annotated[Vec2, _range(positive=True)] = (0.2, 1.0)
    face: Annotated[Vec2, _range()] = (0.6, 2.6)
    gap: NonNeg = 0.4
    amplitude: Annotated[Vec2, _range()] = (0.015, 0.035)
    width: Pos = 2.0

    @model_validator(mode="after")
    def _bounds(self) -> VariedSpec:
        if self.blocks + self.rough + self.flat <= 0:
            raise ValueError("blocks, rough and flat weights are all 0; give at least one a positive weight")
        checks = (
            ("count", self.count[0] >= 1 and self.count[1] <= 6, "integers in [1, 6]"),
            ("height", self.height[1] <= 0.2, "heights up to 0.2 m (the highest swing clears about 0.2 m)"),
            ("depth", self.depth[1] <= 3.0, "depths up to 3.0 m"),
            ("face", self.face[0] >= 0.5, "faces from 0.5 m (the front feet start about 0.47 m ahead)"),
            ("amplitude", self.amplitude[0] >= 0 and self.amplitude[1] <= 0.1, "amplitudes in [0, 0.1] m"),
        )
        for key, ok, allowed in checks:
            if not ok:
                raise ValueError(f"{key}: expected {allowed}, got {show(getattr(self, key))}")
        return self


def _box_kind(value: Any) -> str:
    is_block = isinstance(value, BlockSpec) or (isinstance(value, dict) and "face" in value)
    return "block" if is_block else "box"


BoxEntry = Annotated[
    Annotated[BoxSpec, Tag("box")] | Annotated[BlockSpec, Tag("block")], Discriminator(_box_kind)
]


class TerrainRecipe(_Spec):
    """A terrain description that may contain random parts; `realize` makes it concrete."""

    name: Annotated[str, Field(strict=True, min_length=1)]
    friction: Pos | None = None
    boxes: tuple[BoxEntry, ...] = ()
    rough: RoughSpec | None = None
    stairs: StairsSpec | None = None
    random_blocks: RandomBlocksSpec | None = None
    varied: VariedSpec | None = None

    @model_validator(mode="after")
    def _few_enough_boxes(self) -> TerrainRecipe:
        most = len(self.boxes) + (self.stairs.steps if self.stairs else 0)
        most += self.random_blocks.count[1] if self.random_blocks else 0
        if most > MAX_BOXES:
            raise ValueError(f"up to {most} boxes (boxes + stairs.steps + random_blocks.count); at most {MAX_BOXES}")
        return self


def realize(recipe: TerrainRecipe, rng: np.random.Generator, difficulty: float | None = None) -> Terrain:
    """Make `recipe` concrete. Deterministic given the rng state; only random parts consume draws
    (rough first, then random blocks, then varied). Random blocks avoid each other, not the recipe's fixed boxes.
    `difficulty` in [0, 1] overrides the `varied` section's own (a curriculum's level); other sections ignore it."""
    if difficulty is not None and not 0.0 <= difficulty <= 1.0:
        raise TerrainError(f"difficulty: expected a number in [0, 1], got {difficulty!r}")
    boxes: list[Box] = []
    for spec in recipe.boxes:
        if isinstance(spec, BlockSpec):
            boxes.append(block(spec.face, spec.depth, spec.height, spec.width, spec.y, spec.rgba))
        else:
            boxes.append(Box(spec.center, spec.size, spec.yaw, spec.rgba))
    if (s := recipe.stairs) is not None:
        boxes.extend(stairs(s.start, s.steps, s.rise, s.run, s.top, s.width))
    fields: list[HeightField] = []
    if (r := recipe.rough) is not None:
        fields.append(rough_field(rng, r.x, r.y, r.cell, r.amplitude, r.smoothing, r.ramp, r.flat))
    if (b := recipe.random_blocks) is not None:
        boxes.extend(random_blocks(rng, b.count, b.height, b.depth, b.face, b.gap, b.width))
    if (v := recipe.varied) is not None:
        level = v.difficulty if difficulty is None else difficulty
        weights = (v.blocks, v.rough, v.flat)
        _, more_boxes, more_fields = varied(
            rng, level, weights, v.count, v.height, v.depth, v.face, v.gap, v.amplitude, v.width
        )
        boxes.extend(more_boxes)
        fields.extend(more_fields)
    return Terrain(name=recipe.name, boxes=tuple(boxes), heightfields=tuple(fields), friction=recipe.friction)


def _block_spec(face: float, depth: float, height: float) -> BlockSpec:
    return BlockSpec(face=face, depth=depth, height=height)


SCENARIOS: dict[str, TerrainRecipe] = {
    "flat": TerrainRecipe(name="flat"),
    # The paper's training scene: one 10 cm block, 30 cm deep, its face 1 m ahead.
    "single_block": TerrainRecipe(name="single_block", boxes=(_block_spec(1.0, 0.3, 0.1),)),
    "extra_blocks": TerrainRecipe(
        name="extra_blocks", boxes=(_block_spec(1.0, 0.3, 0.1), _block_spec(2.0, 0.3, 0.1))
    ),
    "wide_block": TerrainRecipe(name="wide_block", boxes=(_block_spec(1.0, 1.0, 0.1),)),
    "rough": TerrainRecipe(name="rough", rough=RoughSpec()),
    "random_blocks": TerrainRecipe(name="random_blocks", random_blocks=RandomBlocksSpec()),
    "stairs": TerrainRecipe(name="stairs", stairs=StairsSpec()),
    # A training distribution: blocks of every height, depth, count and position, rough and flat episodes.
    "varied": TerrainRecipe(name="varied", varied=VariedSpec()),
    # Unseen layouts of the evaluation suite (the fixed-gait checks behind each: benchmarks/suite_check.py).
    # The highest block the best fixed gait (a = 0.4, b = 0.5, omega = 1.5 pi) crosses every time; 0.14 m stops it.
    "tall_block": TerrainRecipe(name="tall_block", boxes=(_block_spec(1.0, 0.3, 0.12),)),
    "low_block": TerrainRecipe(name="low_block", boxes=(_block_spec(1.0, 0.3, 0.06),)),  # a low lift may do
    "steps_up": TerrainRecipe(name="steps_up", stairs=StairsSpec(start=1.0, steps=2, rise=0.06, run=0.5, top=1.0)),
    "block_near": TerrainRecipe(name="block_near", boxes=(_block_spec(0.6, 0.3, 0.1),)),  # single_block, moved
    "block_far": TerrainRecipe(name="block_far", boxes=(_block_spec(1.6, 0.3, 0.1),)),
}


_TAGS: dict[str, type[BaseModel]] = {"box": BoxSpec, "block": BlockSpec}  # tags of the boxes union


def parse_recipe(data: Any, source: str = "terrain", default_name: str = "terrain") -> TerrainRecipe:
    """Validate a YAML-style mapping into a recipe; errors are one-line TerrainErrors naming `source`."""
    if not isinstance(data, dict):
        keys = ", ".join(TerrainRecipe.model_fields)
        raise TerrainError(f"{source}: top level must be a mapping with keys {keys}")
    data = {"name": default_name, **data}
    try:
        return TerrainRecipe.model_validate(data)
    except ValidationError as exc:
        raise TerrainError(format_validation_error(exc, TerrainRecipe, source, tags=_TAGS)) from None


def load_terrain(name_or_path: str | Path) -> TerrainRecipe:
    """A named scenario (see SCENARIOS) or a path to a terrain YAML file (format in the module docstring)."""
    text = str(name_or_path)
    if text in SCENARIOS:
        return SCENARIOS[text]
    path = Path(text)
    if not (path.suffix in (".yaml", ".yml") or path.exists() or "/" in text):
        names = ", ".join(SCENARIOS)
        raise TerrainError(f"unknown terrain '{text}'; valid names: {names} (or a path to a .yaml file)")
    if not path.is_file():
        raise TerrainError(f"{text}: terrain file not found")
    data = read_yaml(path, TerrainError, source=text)
    return parse_recipe(data, source=text, default_name=path.stem)


def make_terrain(name_or_path: str | Path, seed: int | None = 0) -> Terrain:
    """Convenience: `realize(load_terrain(name_or_path), np.random.default_rng(seed))`."""
    return realize(load_terrain(name_or_path), np.random.default_rng(seed))


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
    "load_terrain",
    "make_terrain",
    "parse_recipe",
    "random_blocks",
    "realize",
    "rough_field",
    "stairs",
    "varied",
]
