"""The terrain data model: concrete boxes and height fields, and pure-NumPy queries on them.

`Terrain` is fully realised (no randomness). It answers `height_at` (the height-map sensor's source, so it must
agree with what PyBullet collides with), the labels `obstacle_distance` and `rise_ahead`, and round-trips through
`to_dict` (MCAP metadata). Building it in PyBullet is `builder.build_terrain`: this module imports no PyBullet.
The ground is z = 0; lengths are metres, angles radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache, cached_property
from typing import Any

import numpy as np

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]
Rgba = tuple[float, float, float, float]

BROWN: Rgba = (0.55, 0.35, 0.2, 1.0)  # blocks and steps
SOIL: Rgba = (0.45, 0.4, 0.3, 1.0)  # height fields


class TerrainError(ValueError):
    """A bad terrain file, name or definition; the message is one line naming the entry at fault."""


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


@cache
def _strip_offsets(behind: float, ahead: float, half_width: float) -> tuple[np.ndarray, np.ndarray]:
    """`Terrain.relief`'s sample offsets (m): along the heading every 5 cm from -behind to ahead (a column) and
    across it at the centre and both sides (a row). Cached, since a zone is fixed for a run; read-only."""
    along = np.linspace(-behind, ahead, max(2, math.ceil((ahead + behind) / 0.05) + 1))[:, None]
    across = np.array([-half_width, 0.0, half_width])[None, :]
    along.flags.writeable = False
    across.flags.writeable = False
    return along, across


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

    def relief(self, x: float, y: float, yaw: float, behind: float, ahead: float, half_width: float = 0.3) -> float:
        """How far (m) the terrain rises and falls, max minus min, over the strip from `behind` m behind (x, y) to
        `ahead` m ahead along heading `yaw` (rad), `half_width` m to either side: 0 on level ground, a block's
        height while the strip holds one of its edges. Sampled every 5 cm along and at the centre and both
        sides across; pure NumPy.
        """
        along, across = _strip_offsets(behind, ahead, half_width)
        c, s = math.cos(yaw), math.sin(yaw)
        heights = self.height_at(x + along * c - across * s, y + along * s + across * c)
        return float(heights.max() - heights.min())

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
