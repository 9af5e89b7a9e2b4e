"""The VAE's regression probes (distance to the next rise, its height): R² on known relations, the handling of frames
with no rise in range, and the train-vae report on both modalities."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from hexpipe.config import VaeConfig
from hexpipe.models.probes import knn_r2, ridge_r2, rise_probes
from hexpipe.models.train_vae import train_vae
from hexpipe.models.vae_data import _rise_labels, build_dataset
from hexpipe.recording import Frame


@pytest.fixture(autouse=True)
def _outside_any_repo(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # dvclive would otherwise look for the enclosing repo


def latents(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).normal(size=(n, 8)) * np.arange(1, 9)  # unequal scales: standardised


def test_ridge_r2_is_near_1_for_a_linear_relation_and_near_0_for_noise() -> None:
    w = np.array([0.5, -0.2, 0.0, 0.1, 0.0, 0.0, 0.03, 0.0])
    x_train, x_val = latents(2000, 0), latents(1000, 1)
    noise = np.random.default_rng(2)
    y_train = x_train @ w + 1.0 + noise.normal(0, 0.01, 2000)
    y_val = x_val @ w + 1.0 + noise.normal(0, 0.01, 1000)
    assert ridge_r2(x_train, y_train, x_val, y_val) > 0.99
    unrelated_train, unrelated_val = noise.normal(size=2000), noise.normal(size=1000)
    assert abs(ridge_r2(x_train, unrelated_train, x_val, unrelated_val)) < 0.02
    assert math.isnan(ridge_r2(x_train, y_train, x_val[:1], y_val[:1]))  # nothing to score
    assert math.isnan(ridge_r2(x_train, y_train, x_val, np.ones(1000)))  # no spread: R² undefined


def test_knn_r2_reads_a_non_linear_code_that_ridge_misses() -> None:
    x_train, x_val = latents(3000, 3)[:, :2], latents(500, 4)[:, :2]
    y_train, y_val = np.cos(x_train[:, 0]), np.cos(x_val[:, 0])  # even in x0: no linear trace
    assert knn_r2(x_train, y_train, x_val, y_val) > 0.8
    assert ridge_r2(x_train, y_train, x_val, y_val) < 0.05


def test_frames_without_a_rise_in_range_are_left_out_of_the_regressions() -> None:
    x_train, x_val = latents(600, 5), latents(300, 6)
    distance = lambda x: 0.8 + 0.1 * x[:, 1]  # noqa: E731
    height = lambda x: 0.08 + 0.005 * x[:, 2]  # noqa: E731
    d_train, h_train, d_val, h_val = distance(x_train), height(x_train), distance(x_val), height(x_val)
    # a third of the frames see nothing ahead (inf, nan), told apart by latent 0; a few are unlabelled (nan, nan)
    for x, d, h in ((x_train, d_train, h_train), (x_val, d_val, h_val)):
        empty = x[:, 0] > 0.5
        d[empty], h[empty] = np.inf, np.nan
        d[:10], h[:10] = np.nan, np.nan
    out = rise_probes(x_train, (d_train, h_train), x_val, (d_val, h_val))
    assert out["rise_distance_r2"] > 0.99 and out["rise_height_r2"] > 0.99
    assert out["rise_val_frames"] == np.isfinite(d_val).sum()
    assert out["rise_val_share"] == pytest.approx(np.isfinite(d_val).sum() / (300 - 10))
    assert out["rise_in_range_accuracy"] > 0.95 > out["rise_in_range_baseline"]


def test_labels_from_step_messages() -> None:
    assert _rise_labels({"rise_distance": 0.7, "rise_height": 0.1}) == (0.7, 0.1)
    distance, height = _rise_labels({"rise_distance": None, "rise_height": None})  # nothing in range
    assert math.isinf(distance) and math.isnan(height)
    assert all(math.isnan(v) for v in _rise_labels({"obstacle_distance": 1.0}))  # recorded before the labels


def frames(modality: str, episodes: int = 10, steps: int = 24, seed: int = 0) -> Iterator[Frame]:
    """Each episode walks up to one block of its own height; the sensor shows it 'distance' ahead."""
    rng = np.random.default_rng(seed)
    for e in range(episodes):
        height = rng.uniform(0.04, 0.12)
        start = rng.uniform(1.6, 2.0)
        for t in range(steps):
            d = start * (1 - t / steps)
            seen = d <= 1.4
            hm = rng.normal(0.0, 0.003, (32, 32)).astype(np.float32)
            img = np.full((48, 48, 3), 120, np.uint8)
            if seen:
                row = round((d + 0.2) / 1.6 * 32)
                hm[row:] += height
                img[: int((1.6 - d) / 1.8 * 48), :] = (int(1000 * height) + 30, 90, 40)
            yield Frame(
                episode=f"ep{e:02d}", step=t, sensors={modality: img if modality == "rgb" else hm},
                meta={"obstacle_distance": d, "rise_distance": d if seen else None,
                      "rise_height": height if seen else None},
            )


def test_dataset_keeps_the_rise_labels() -> None:
    data = build_dataset(frames("heightmap", episodes=2), "heightmap", 32)
    assert data.rise_distance.shape == data.rise_height.shape == (48,)
    seen = np.isfinite(data.rise_distance)
    assert 0 < seen.sum() < 48 and np.isnan(data.rise_height[~seen]).all()
    assert (data.rise_height[seen] >= 0.04).all()


@pytest.mark.parametrize("modality", ["heightmap", "rgb"])
def test_train_vae_reports_the_rise_probes(modality: str, tmp_path: Path) -> None:
    cfg = VaeConfig(modality=modality, image_size=32, batch_size=32, epochs=3, out_dir=str(tmp_path / "model"),
                    report_dir=str(tmp_path / "report"), data_dir=str(tmp_path / "none"))
    metrics = train_vae(cfg, frames(modality))
    for key in ("rise_distance_r2", "rise_height_r2", "rise_distance_knn_r2", "rise_height_knn_r2"):
        assert math.isfinite(metrics[f"probe/{key}"]) and metrics[f"probe/{key}"] <= 1.0
    assert metrics["probe/rise_val_frames"] > 0
    assert (tmp_path / "report" / "plots" / "images" / "rise_probes.png").is_file()


def test_logged_steps_carry_the_rise_labels(tmp_path: Path) -> None:
    from hexpipe.config import TaskConfig
    from hexpipe.envs.hexapod import HexapodEnv
    from hexpipe.recording.episode import EpisodeLog
    from hexpipe.recording.reader import iter_frames

    env = HexapodEnv("single_block", task=TaskConfig(sensors=()))  # block face at 1.0 m, 0.10 m high
    env.reset(seed=0)
    with EpisodeLog(env, tmp_path / "ep.mcap", {}, sensors=("heightmap",)) as log:
        log.step(0.0, force=True)
        for _ in range(3):
            _, reward, *_ = env.step(np.zeros(3))
            log.step(reward)
    x = float(env.robot.base_state()[0][0])
    far = HexapodEnv("single_block", task=TaskConfig(sensors=()))
    far.reset(seed=0)
    p = far._p  # put the robot 1.6 m before the face: beyond the height map's 1.4 m reach, within 3 m
    p.resetBasePositionAndOrientation(far.robot.body, [-0.6, 0.0, 0.3], [0, 0, 0, 1], physicsClientId=far.client)
    labels = far.terrain_labels()
    assert labels["obstacle_distance"] == pytest.approx(1.6, abs=2e-3)
    assert math.isinf(labels["rise_distance"]) and math.isnan(labels["rise_height"])
    far.close()
    env.close()
    frames = list(iter_frames(tmp_path / "ep.mcap", ("heightmap",)))
    assert len(frames) == 4
    assert frames[-1].meta["rise_distance"] == pytest.approx(1.0 - x, abs=2e-3)
    assert all(f.meta["obstacle_distance"] == f.meta["rise_distance"] for f in frames)  # within reach: the same
    assert all(f.meta["rise_height"] == pytest.approx(0.1) for f in frames)
