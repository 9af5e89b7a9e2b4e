"""The evaluation suite's unseen layouts: geometry as specified, and physically meaningful (a fixed low gait stops
where a high one crosses; benchmarks/suite_check.py measures the same on more seeds and gaits)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from hexpipe.config import CpgConfig, Params, TaskConfig, load_params
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.evaluation.suite import evaluation_suite
from hexpipe.sim.terrain import SCENARIOS, realize

ROOT = Path(__file__).resolve().parents[1]
NEW = ("low_block", "tall_block", "steps_up", "block_near", "block_far")


def faces(name: str) -> list[tuple[float, float, float]]:
    """(face x, depth, top height) of every box of a named scenario, along x (m)."""
    t = realize(SCENARIOS[name], np.random.default_rng(0))
    return sorted((round(b.center[0] - b.size[0] / 2, 9), round(b.size[0], 9), round(b.top, 9)) for b in t.boxes)


def test_new_layouts_have_their_faces_and_heights():
    assert faces("tall_block") == [(1.0, 0.3, 0.12)]
    assert faces("low_block") == [(1.0, 0.3, 0.06)]
    assert faces("block_near") == [(0.6, 0.3, 0.1)]
    assert faces("block_far") == [(1.6, 0.3, 0.1)]
    assert faces("steps_up") == [(1.0, 0.5, 0.06), (1.5, 1.0, 0.12)]  # two 6 cm rises, the top 1 m long
    steps = realize(SCENARIOS["steps_up"], np.random.default_rng(0))
    np.testing.assert_allclose(steps.height_at(np.array([0.99, 1.01, 1.49, 1.51, 2.49, 2.51]), 0.0),
                               [0.0, 0.06, 0.06, 0.12, 0.12, 0.0], atol=1e-12)


def test_default_suite_is_flat_the_paper_scenes_and_the_unseen_layouts():
    params = load_params(ROOT / "params.yaml")
    assert params.eval.terrains == Params().eval.terrains  # params.yaml and the code defaults agree
    stems = [s.stem for s in evaluation_suite(params)]
    assert stems[:5] == ["flat", "single_block", "extra_blocks", "wide_block", "rough"]
    assert set(NEW) <= set(stems)


def fixed_gait(terrain: str, a: float, b: float, seed: int = 0) -> tuple[str, float]:
    """(termination, distance) of one zero-action episode at omega = 1.5 pi."""
    gait = (a, b, 1.5 * math.pi)
    env = HexapodEnv(terrain, cpg=CpgConfig().holding(gait), initial_cpg=gait, task=TaskConfig(sensors=()))
    env.reset(seed=seed)
    try:
        while True:
            _, _, terminated, truncated, info = env.step(np.zeros(3))
            if terminated or truncated:
                return info["termination"], info["distance"]
    finally:
        env.close()


@pytest.mark.parametrize("terrain", NEW)
def test_a_low_gait_stops_and_a_high_gait_crosses(terrain):
    termination, distance = fixed_gait(terrain, 0.25, 0.15)  # the paper's low initial gait (cpg.initial before 89e3243)
    assert termination == "stuck" and distance < 1.2
    assert fixed_gait(terrain, 0.4, 0.5)[0] == "goal"  # the grid's best fixed gait under the old ranking


def test_the_tall_block_needs_more_lift_than_the_training_block():
    assert fixed_gait("tall_block", 0.4, 0.3)[0] == "stuck"  # b = 0.3 crosses single_block (the premise)
    assert fixed_gait("low_block", 0.4, 0.25)[0] == "goal"  # and a low block needs less
