"""Terrain recipes: validated descriptions (named scenarios and YAML files) that `realize` makes concrete.

A `TerrainRecipe` may hold random parts; `realize(recipe, rng)` turns it into a `Terrain`, deterministically given
the generator state. `load_terrain` takes a scenario name (`SCENARIOS`) or a YAML path (format in the package
docstring). A malformed file raises `TerrainError` with one line naming the file and the entry at fault.
"""

from __future__ import annotations

import math
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

from hexpipe.sim.terrain.model import BROWN, Box, HeightField, Rgba, Terrain, TerrainError, Vec2, Vec3
from hexpipe.sim.terrain.primitives import block, random_blocks, rough_field, stairs, varied
from hexpipe.validation import format_validation_error, read_yaml, show

# Bounds on what a terrain file may ask for, so that a typo gives an error instead of a hang or an OOM kill.
MAX_GRID_NODES = 250_000  # height-field nodes: PyBullet builds 1M nodes in ~6 s, 4M in ~40 s (at every reset)
MAX_NOISE_WORK = 200_000_000  # rough: padded noise nodes x Gaussian kernel taps (~1 s of NumPy, ~32 MB)
MAX_BOXES = 200  # boxes of one terrain, all parts together: each step's height map tests every box
MAX_VALUE = 1000.0  # every number of a terrain file (m, rad or friction) within +-this: PyBullet needs sane sizes


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
    # `varied` with more open ground (flat 0.4, rough 0.1, blocks 0.5): the lift price is charged on 0.54 of the
    # course instead of 0.29, so walking high everywhere costs something (reports/experiments/README.md, `open`).
    "varied_open": TerrainRecipe(name="varied_open", varied=VariedSpec(blocks=0.5, rough=0.1, flat=0.4)),
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
