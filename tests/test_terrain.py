"""Terrain: height_at agrees with PyBullet ray casts, recipes are deterministic, YAML errors are one line."""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pybullet as p
import pytest

from hexpipe.sim.terrain import (
    SCENARIOS,
    Box,
    HeightField,
    Terrain,
    TerrainError,
    block,
    build_terrain,
    load_terrain,
    realize,
    stairs,
)

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "terrains").glob("*.yaml"))


@pytest.fixture
def client() -> Iterator[int]:
    cid = p.connect(p.DIRECT)
    yield cid
    p.disconnect(cid)


def raycast(terrain: Terrain, client: int, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Build the terrain and cast a ray straight down at every (x, y); the hit heights (m)."""
    build_terrain(terrain, client)
    starts = [(a, b, 3.0) for a, b in zip(x, y, strict=True)]
    ends = [(a, b, -1.0) for a, b in zip(x, y, strict=True)]
    hits = p.rayTestBatch(starts, ends, physicsClientId=client)
    assert all(h[0] >= 0 for h in hits), "a ray missed the terrain (the ground plane should be everywhere)"
    return np.array([h[3][2] for h in hits])


def jagged_terrain() -> Terrain:
    """Yawed and overlapping boxes on top of a non-square white-noise height field that dips below ground:
    a wrong diagonal, axis order or z offset in the height field shows up as centimetre errors."""
    rng = np.random.default_rng(7)
    field = HeightField(origin=(0.3, -0.9), cell=0.1, heights=rng.uniform(-0.1, 0.3, (17, 11)))
    boxes = (
        Box(center=(1.0, 0.2, 0.1), size=(0.4, 0.8, 0.2), yaw=0.7),
        Box(center=(1.2, -0.3, 0.2), size=(0.3, 0.3, 0.4), yaw=-2.0),
        Box(center=(2.5, 0.0, 0.6), size=(0.5, 0.5, 0.2)),  # floating: its top still counts
        block(2.8, 0.4, 0.05),
    )
    return Terrain(name="jagged", boxes=boxes, heightfields=(field,), friction=0.7)


def all_terrains() -> list[tuple[str, Terrain]]:
    named = [(name, realize(recipe, np.random.default_rng(3))) for name, recipe in SCENARIOS.items()]
    files = [(path.name, realize(load_terrain(str(path)), np.random.default_rng(3))) for path in EXAMPLES]
    return [*named, *files, ("jagged", jagged_terrain())]


TERRAINS = all_terrains()


def test_example_files_exist() -> None:
    assert {"stairs_up.yaml", "two_low_blocks.yaml"} <= {p.name for p in EXAMPLES}


@pytest.mark.parametrize(("label", "terrain"), TERRAINS, ids=[label for label, _ in TERRAINS])
def test_height_at_matches_raycast(label: str, terrain: Terrain, client: int) -> None:
    rng = np.random.default_rng(0)
    x = rng.uniform(-0.5, 4.5, 1500)
    y = rng.uniform(-2.0, 2.0, 1500)
    err = np.abs(raycast(terrain, client, x, y) - terrain.height_at(x, y))
    tolerance = 5e-3 if terrain.heightfields else 1e-3
    worst = int(err.argmax())
    assert err[worst] < tolerance, (
        f"{label}: |raycast - height_at| = {err[worst]:.4f} at {x[worst], y[worst]}"
    )


def test_build_returns_bodies_and_sets_friction(client: int) -> None:
    terrain = jagged_terrain()
    ids = build_terrain(terrain, client)
    assert len(ids) == 1 + len(terrain.boxes) + len(terrain.heightfields)  # ground first
    for body in ids:
        assert p.getDynamicsInfo(body, -1, physicsClientId=client)[1] == pytest.approx(0.7)
        assert p.getBodyInfo(body, physicsClientId=client) is not None


def test_height_at_shapes_and_values() -> None:
    terrain = realize(SCENARIOS["single_block"], np.random.default_rng(0))
    assert terrain.height_at(1.15, 0.0) == pytest.approx(0.10)
    assert terrain.height_at(0.5, 0.0) == 0.0
    assert terrain.height_at(1.15, 1.2) == 0.0  # beside the block (it spans y in [-1, 1])
    gx, gy = np.meshgrid(np.linspace(0, 2, 32), np.linspace(-1, 1, 32), indexing="ij")
    assert terrain.height_at(gx, gy).shape == (32, 32)
    assert terrain.height_at(np.linspace(0, 2, 5)[:, None], 0.0).shape == (5, 1)


def test_named_dimensions() -> None:
    def spans(name: str) -> list[tuple[float, float, float]]:
        t = realize(SCENARIOS[name], np.random.default_rng(0))
        return [
            (round(b.center[0] - b.size[0] / 2, 9), round(b.size[0], 9), round(b.size[2], 9)) for b in t.boxes
        ]

    assert spans("single_block") == [(1.0, 0.3, 0.1)]
    assert spans("extra_blocks") == [(1.0, 0.3, 0.1), (2.0, 0.3, 0.1)]
    assert spans("wide_block") == [(1.0, 1.0, 0.1)]
    assert spans("flat") == []
    t = realize(SCENARIOS["single_block"], np.random.default_rng(0))
    assert t.boxes[0].size[1] == 2.0 and t.boxes[0].center[1] == 0.0


def test_stairs_treads() -> None:
    terrain = Terrain(name="s", boxes=stairs(1.0, steps=3, rise=0.05, run=0.35, top=2.0))
    treads = terrain.height_at(np.array([0.9, 1.2, 1.5, 1.9, 3.0, 4.1]), np.zeros(6))
    np.testing.assert_allclose(treads, [0.0, 0.05, 0.10, 0.15, 0.15, 0.0], atol=1e-12)


def test_rough_is_bumpy_bounded_and_flat_at_the_start() -> None:
    terrain = realize(SCENARIOS["rough"], np.random.default_rng(0))
    (field,) = terrain.heightfields
    assert np.allclose(field.extent, ((0.4, 4.0), (-1.5, 1.5)))
    assert field.cell == 0.05
    heights = field.heights
    assert heights.min() >= 0.0 and heights.max() <= 2 * 0.035 + 1e-12
    assert heights[20:50, 20:40].std() > 0.005  # actually bumpy in the middle
    x = np.linspace(-0.3, 0.45, 50)
    assert np.abs(terrain.height_at(x, np.zeros_like(x))).max() < 1e-3  # spawn area flat


def test_same_seed_same_terrain_different_seed_different() -> None:
    for name in SCENARIOS:
        a = realize(SCENARIOS[name], np.random.default_rng(42))
        b = realize(SCENARIOS[name], np.random.default_rng(42))
        assert a == b, name
    rb = SCENARIOS["random_blocks"]
    assert realize(rb, np.random.default_rng(1)) != realize(rb, np.random.default_rng(2))
    rough = SCENARIOS["rough"]
    assert realize(rough, np.random.default_rng(1)) != realize(rough, np.random.default_rng(2))


def test_random_blocks_never_overlap() -> None:
    counts = set()
    for seed in range(50):
        terrain = realize(SCENARIOS["random_blocks"], np.random.default_rng(seed))
        spans = sorted((b.center[0] - b.size[0] / 2, b.center[0] + b.size[0] / 2) for b in terrain.boxes)
        counts.add(len(spans))
        assert 1 <= len(spans) <= 3
        for box in terrain.boxes:
            face = box.center[0] - box.size[0] / 2
            assert 0.8 - 1e-9 <= face <= 2.6 + 1e-9
            assert 0.2 <= box.size[0] <= 1.0 and 0.06 <= box.size[2] <= 0.12
            assert box.size[1] == 2.0 and box.center[1] == 0.0
        for (_, end), (start, _) in itertools.pairwise(spans):
            assert start - end >= 0.4 - 1e-9, f"seed {seed}: gap {start - end:.3f} m"
    assert counts == {1, 2, 3}


@pytest.mark.parametrize(("label", "terrain"), TERRAINS, ids=[label for label, _ in TERRAINS])
def test_dict_round_trip(label: str, terrain: Terrain) -> None:
    restored = Terrain.from_dict(json.loads(json.dumps(terrain.to_dict())))
    assert restored == terrain
    assert type(restored.to_dict()["heightfields"]) is list


def test_example_yaml_contents() -> None:
    two = realize(load_terrain(str(EXAMPLES[0].parent / "two_low_blocks.yaml")), np.random.default_rng(0))
    assert two.name == "two_low_blocks"
    assert [round(b.center[0] - b.size[0] / 2, 9) for b in two.boxes] == [1.0, 2.0]
    up = realize(load_terrain(str(EXAMPLES[0].parent / "stairs_up.yaml")), np.random.default_rng(0))
    assert up.friction == 1.0
    assert up.height_at(3.0, 0.0) == pytest.approx(0.15)


def test_obstacle_distance() -> None:
    single = realize(SCENARIOS["single_block"], np.random.default_rng(0))
    assert single.obstacle_distance(0.0, 0.0, 0.0) == pytest.approx(1.0, abs=2e-3)
    assert single.obstacle_distance(0.5, 0.3, 0.0) == pytest.approx(0.5, abs=2e-3)
    assert single.obstacle_distance(0.0, 0.0, math.pi) == math.inf  # facing away
    assert single.obstacle_distance(0.0, 0.0, math.pi / 2) == math.inf  # sideways, beside the block
    assert single.obstacle_distance(0.0, 0.0, 0.0, max_range=0.9) == math.inf
    # Diagonal heading: the face is reached after 1 / cos(yaw) metres.
    assert single.obstacle_distance(0.0, 0.0, 0.3) == pytest.approx(1.0 / math.cos(0.3), abs=2e-3)
    extra = realize(SCENARIOS["extra_blocks"], np.random.default_rng(0))
    assert extra.obstacle_distance(1.5, 0.0, 0.0) == pytest.approx(0.5, abs=2e-3)
    # Rises are measured from the height under the start: from on top of the first block the second
    # (equally high) one is no obstacle.
    assert extra.obstacle_distance(1.1, 0.0, 0.0) == math.inf
    flat = realize(SCENARIOS["flat"], np.random.default_rng(0))
    assert flat.obstacle_distance(0.0, 0.0, 0.0) == math.inf


def test_unknown_name_lists_valid_names() -> None:
    with pytest.raises(TerrainError) as info:
        load_terrain("single_blok")
    message = str(info.value)
    assert "single_blok" in message and all(name in message for name in SCENARIOS)


BAD_FILES = [
    (
        "boxes:\n  - {face: 1.0, depth: 0.3, height: 0.1}\n  - {center: [1, 0, 0], size: [0.3, -2]}\n",
        "boxes[1].size",
    ),
    ("boxes:\n  - {face: 1.0, depth: -0.3, height: 0.1}\n", "boxes[0].depth"),
    ("boxes:\n  - {center: [1, 0, 0], size: [1, 1, 1], colour: red}\n", "boxes[0].colour"),
    ("bloks: []\n", "bloks"),
    ("friction: high\n", "friction"),
    ("rough: {x: [4.0, 0.4]}\n", "rough.x"),
    ("rough: {cell: 0.0}\n", "rough.cell"),
    ("stairs: {steps: 0}\n", "stairs.steps"),
    ("stairs: {steps: 2.5}\n", "stairs.steps"),
    ("random_blocks: {count: [3, 1]}\n", "random_blocks.count"),
    ("random_blocks: {height: [0.1]}\n", "random_blocks.height"),
    ("boxes: {face: 1.0}\n", "boxes"),
    ("boxes:\n  - {center: [1, 0, 0]}\n", "boxes[0].size"),
    ("- just\n- a list\n", "top level"),
    ("boxes: [\n", "line"),
    ("", "top level"),
]


@pytest.mark.parametrize(("text", "entry"), BAD_FILES, ids=[entry for _, entry in BAD_FILES])
def test_malformed_file_is_one_line_naming_the_entry(text: str, entry: str, tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(TerrainError) as info:
        load_terrain(str(path))
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(str(path)), message
    assert entry in message, message


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nope.yaml"
    with pytest.raises(TerrainError, match="not found") as info:
        load_terrain(str(path))
    assert str(path) in str(info.value)


def test_size_error_text(tmp_path: Path) -> None:
    path = tmp_path / "x.yaml"
    path.write_text(
        "boxes:\n  - {face: 1.0, depth: 0.3, height: 0.1}\n  - {center: [1, 0, 0], size: [0.3, -2]}\n"
    )
    with pytest.raises(TerrainError) as info:
        load_terrain(str(path))
    assert str(info.value) == f"{path}: boxes[1].size: expected 3 positive numbers (|x| <= 1000), got [0.3, -2]"


def test_bad_concrete_data_raises_terrain_error() -> None:
    with pytest.raises(TerrainError):
        Box(center=(0, 0, 0), size=(1, -1, 1))
    with pytest.raises(TerrainError):
        HeightField(origin=(0, 0), cell=0.1, heights=np.zeros(5))
    with pytest.raises(TerrainError):
        Terrain.from_dict({"name": "x", "boxes": [{"center": [0, 0]}]})
    assert issubclass(TerrainError, ValueError)


def test_terrain_is_immutable() -> None:
    terrain = jagged_terrain()
    with pytest.raises(ValueError):
        terrain.heightfields[0].heights[0, 0] = 1.0
    with pytest.raises(AttributeError):
        terrain.name = "other"  # type: ignore[misc]
