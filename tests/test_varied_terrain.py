"""The `varied` training terrain (seeded, bounded, harder with difficulty) and the rise labels for the VAE probes."""

import itertools
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.sim.terrain import (
    SCENARIOS,
    TerrainError,
    load_terrain,
    parse_recipe,
    realize,
    varied,
)

VARIED = SCENARIOS["varied"]
LEVELS = (0.0, 0.25, 0.5, 0.75, 1.0)


def draws(difficulty: float, seeds: int = 300) -> dict[str, list]:
    """Per variant, what `varied` drew over many seeds: blocks (count, heights), rough (max height)."""
    out: dict[str, list] = {"blocks": [], "rough": [], "flat": []}
    for seed in range(seeds):
        kind, boxes, fields = varied(np.random.default_rng(seed), difficulty)
        if kind == "blocks":
            out[kind].append((len(boxes), [b.size[2] for b in boxes], boxes))
        elif kind == "rough":
            out[kind].append(float(fields[0].heights.max()))
        else:
            out[kind].append((boxes, fields))
    return out


def test_same_seed_same_terrain_and_every_variant_is_drawn() -> None:
    for seed in range(20):
        assert realize(VARIED, np.random.default_rng(seed)) == realize(VARIED, np.random.default_rng(seed))
    terrains = [realize(VARIED, np.random.default_rng(seed)) for seed in range(40)]
    assert len({(t.boxes, t.heightfields) for t in terrains}) > 30
    seen = draws(1.0, seeds=100)
    assert all(seen[kind] for kind in ("blocks", "rough", "flat"))
    assert all(boxes == () and fields == () for boxes, fields in seen["flat"])
    assert len(seen["blocks"]) > len(seen["rough"]) > len(seen["flat"])  # weights 0.7, 0.2, 0.1


def test_env_episodes_are_seeded_and_difficulty_comes_through_reset_options() -> None:
    env = HexapodEnv("varied")
    env.reset(seed=5)
    first = env.terrain
    env.reset(seed=5)
    assert env.terrain == first
    heights = []
    for level in (0.0, 1.0):
        for seed in range(12):
            env.reset(seed=seed, options={"difficulty": level})
            heights += [(level, b.size[2]) for b in env.terrain.boxes]
    env.close()
    assert {h for level, h in heights if level == 0.0} == {0.04}  # the lowest blocks only
    assert max(h for level, h in heights if level == 1.0) > 0.08


def test_draws_respect_their_bounds_at_every_difficulty() -> None:
    for level in LEVELS:
        seen = draws(level, seeds=150)
        top_height = 0.04 + 0.08 * level
        top_count = round(1 + 2 * level)
        for count, heights, boxes in seen["blocks"]:
            assert 1 <= count <= top_count
            assert all(0.04 - 1e-12 <= h <= top_height + 1e-12 for h in heights)
            spans = sorted((b.center[0] - b.size[0] / 2, b.center[0] + b.size[0] / 2) for b in boxes)
            assert all(0.6 - 1e-9 <= lo <= 2.6 + 1e-9 and 0.2 <= hi - lo <= 1.0 for lo, hi in spans)
            assert all(b_lo - a_hi >= 0.4 - 1e-9 for (_, a_hi), (b_lo, _) in itertools.pairwise(spans))
        amplitude = 0.015 + 0.02 * level
        assert all(0 < peak <= 2 * amplitude + 1e-12 for peak in seen["rough"])


def test_difficulty_raises_heights_counts_and_bumps_monotonically() -> None:
    mean_height, mean_count, max_height, mean_bump = [], [], [], []
    for level in LEVELS:
        seen = draws(level)
        heights = [h for _, hs, _ in seen["blocks"] for h in hs]
        mean_height.append(np.mean(heights))
        max_height.append(max(heights))
        mean_count.append(np.mean([c for c, _, _ in seen["blocks"]]))
        mean_bump.append(np.mean(seen["rough"]))
    for series in (mean_height, mean_count, max_height, mean_bump):
        assert np.all(np.diff(series) >= 0), series
        assert series[-1] > series[0], series
    assert max_height[-1] > 0.115 and mean_count[0] == 1


@pytest.mark.parametrize(
    ("text", "entry"),
    [
        ("varied: {difficulty: 1.5}\n", "varied.difficulty"),
        ("varied: {height: [0.04, 0.3]}\n", "varied: height"),
        ("varied: {count: [1, 9]}\n", "varied: count"),
        ("varied: {count: [0, 2]}\n", "varied: count"),
        ("varied: {face: [0.2, 2.6]}\n", "varied: face"),
        ("varied: {amplitude: [0.0, 0.2]}\n", "varied: amplitude"),
        ("varied: {depth: [1.0, 0.2]}\n", "varied.depth"),
        ("varied: {blocks: 0, rough: 0, flat: 0}\n", "weights are all 0"),
        ("varied: {flat: -1}\n", "varied.flat"),
        ("varied: {hills: 1}\n", "varied.hills"),
    ],
)
def test_bad_varied_settings_are_one_line_errors(text: str, entry: str, tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(TerrainError) as info:
        load_terrain(str(path))
    assert "\n" not in str(info.value) and entry in str(info.value), str(info.value)


def test_a_varied_yaml_file_and_a_bad_difficulty_override(tmp_path: Path) -> None:
    path = tmp_path / "course.yaml"
    path.write_text("varied: {difficulty: 0.0, blocks: 1, rough: 0, flat: 0, count: [2, 4]}\n")
    terrain = realize(load_terrain(str(path)), np.random.default_rng(0))
    assert len(terrain.boxes) == 2 and {b.size[2] for b in terrain.boxes} == {0.04}
    with pytest.raises(TerrainError, match=r"difficulty: expected a number in \[0, 1\], got 1\.2"):
        realize(VARIED, np.random.default_rng(0), difficulty=1.2)


def _fixed(name: str):
    """A scenario without random parts, made concrete."""
    return realize(SCENARIOS[name], np.random.default_rng(0))


def test_rise_ahead_labels_distance_and_height_on_known_terrains() -> None:
    single = _fixed("single_block")  # 0.10 m high, face at 1.0 m
    assert single.rise_ahead(0.0, 0.0, 0.0, max_range=1.4) == pytest.approx((1.0, 0.1), abs=2e-3)
    assert single.rise_ahead(0.0, 0.0, 0.0, max_range=0.9) == (math.inf, pytest.approx(math.nan, nan_ok=True))
    assert single.rise_ahead(0.6, 0.2, 0.0, max_range=1.4) == pytest.approx((0.4, 0.1), abs=2e-3)
    stairs = _fixed("stairs")  # risers of 0.05 m every 0.35 m from x = 1.0
    assert stairs.rise_ahead(0.0, 0.0, 0.0, max_range=1.4) == pytest.approx((1.0, 0.05), abs=2e-3)
    assert stairs.rise_ahead(1.1, 0.0, 0.0, max_range=1.4) == pytest.approx((0.25, 0.05), abs=2e-3)  # one riser
    extra = _fixed("extra_blocks")
    distance, height = extra.rise_ahead(1.1, 0.0, 0.0, max_range=1.4)  # on top of the first block
    assert math.isinf(distance) and math.isnan(height)  # the second block is no higher: no rise
    text = "boxes: [{face: 0.8, depth: 0.3, height: 0.05}, {face: 1.5, depth: 0.3, height: 0.12}]"
    two = realize(parse_recipe(yaml.safe_load(text)), np.random.default_rng(0))
    assert two.rise_ahead(0.0, 0.0, 0.0, max_range=1.4) == pytest.approx((0.8, 0.05), abs=2e-3)  # the first rise
    assert two.rise_ahead(1.2, 0.0, 0.0, max_range=1.4) == pytest.approx((0.3, 0.12), abs=2e-3)


def test_relief_is_the_rise_and_fall_within_the_strip_around_the_body() -> None:
    """What waives the lift price (task.lift_free_zone): a block's height while the strip holds one of its edges."""
    single = _fixed("single_block")  # 0.10 m high, 0.30 m deep, face at 1.0 m
    zone = (0.4, 0.5)  # m behind, m ahead
    assert single.relief(0.0, 0.0, 0.0, *zone) == 0.0  # level ground; the face is 1.0 m ahead
    assert single.relief(0.6, 0.0, 0.0, *zone) == pytest.approx(0.1)  # the face within 0.5 m ahead
    assert single.relief(1.6, 0.0, 0.0, *zone) == pytest.approx(0.1)  # the back edge within 0.4 m behind
    assert single.relief(1.8, 0.0, 0.0, *zone) == 0.0  # past it
    assert single.relief(0.55, 0.0, math.pi, *zone) == 0.0  # facing back, the face is behind and beyond 0.4 m
    assert single.relief(0.55, 0.0, math.pi, 0.5, 0.5) == pytest.approx(0.1)
    wide = _fixed("wide_block")  # 1.0 m deep: its top is level
    assert wide.relief(1.5, 0.0, 0.0, *zone) == 0.0
    assert _fixed("rough").relief(1.5, 0.0, 0.0, *zone) > 0.03  # rough ground is uneven everywhere


def test_varied_open_draws_four_times_the_flat_courses_of_varied() -> None:
    """`varied_open` (flat 0.4, rough 0.1, blocks 0.5) is `varied` with more open ground, where the lift price is
    charged: over the same 400 seeds it draws about 40% flat courses against about 10%, and blocks no other way."""

    def kinds(recipe) -> dict[str, int]:
        counts = {"blocks": 0, "rough": 0, "flat": 0}
        for seed in range(400):
            t = realize(recipe, np.random.default_rng(seed), 1.0)
            counts["blocks" if t.boxes else "rough" if t.heightfields else "flat"] += 1
        return counts

    opened, base = kinds(SCENARIOS["varied_open"]), kinds(VARIED)
    assert 0.33 < opened["flat"] / 400 < 0.47 and 0.06 < base["flat"] / 400 < 0.14
    assert 0.42 < opened["blocks"] / 400 < 0.58 and opened["rough"] < base["rough"]
    assert SCENARIOS["varied_open"].varied.height == VARIED.varied.height  # the same blocks when it draws them
    assert SCENARIOS["varied_open"].varied.depth == VARIED.varied.depth
