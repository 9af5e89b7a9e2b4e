"""VAE model, preprocessing, dataset assembly, resumable training, encoder export and the train_vae stage.

Synthetic rollouts stand in for MCAP files: each episode approaches (or never meets) a 10 cm block, so the
frames carry a known "block within 1 m" label for the probe.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

import hexpipe.models.train_vae as stage
from hexpipe.config import VaeConfig
from hexpipe.models.probes import active_dims, linear_probe
from hexpipe.models.train_vae import train_step, train_vae
from hexpipe.models.vae import (
    ConvVAE,
    EncoderError,
    encoder_config,
    export_encoder,
    load_encoder,
    preprocess,
    vae_loss,
)
from hexpipe.models.vae_data import VaeDataError, build_dataset, load_dataset, split_by_episode
from hexpipe.recording import EpisodeWriter, Frame
from hexpipe.sensors import Message

HM_NEAR, HM_FAR, HM_CELLS = -0.2, 1.4, 32  # synthetic height map: 32x32 cells covering -0.2..1.4 m ahead
SENSE_RANGE_M = 3.0  # obstacle_distance is inf beyond this, as in the env


def _heightmap(distance: float, rng: np.random.Generator) -> np.ndarray:
    """Flat ground with 4 mm noise, plus a 0.10 m block 0.3 m deep starting `distance` m ahead."""
    hm = rng.normal(0.0, 0.004, (HM_CELLS, HM_CELLS)).astype(np.float32)
    if math.isfinite(distance):
        row = round((distance - HM_NEAR) / (HM_FAR - HM_NEAR) * HM_CELLS)
        if row < HM_CELLS:
            hm[max(row, 0) : row + 6] += 0.10
    return hm


def _rgb(distance: float, rng: np.random.Generator, size: int = 48) -> np.ndarray:
    """Grey ground; a brown band for the block, lower in the image the closer it is."""
    img = np.clip(rng.normal(120, 8, (size, size, 3)), 0, 255).astype(np.uint8)
    if math.isfinite(distance) and distance < 1.6:
        row = int((1.6 - distance) / 1.8 * size)
        img[max(row - 6, 0) : row, :] = (150, 90, 40)
    return img


def synthetic_frames(
    episodes: int = 12, steps: int = 20, seed: int = 0, modalities: tuple[str, ...] = ("heightmap",)
) -> Iterator[Frame]:
    """Every 4th episode is flat; the others walk from beyond the 3 m sensing range (obstacle_distance inf)
    to within ~0.3 m of a block, so each has frames of both probe classes and of the 1-3 m gap between."""
    rng = np.random.default_rng(seed)
    for e in range(episodes):
        flat = e % 4 == 3
        start = rng.uniform(3.2, 3.5)
        for t in range(steps):
            d = start * (1 - t / steps)
            if flat or d > SENSE_RANGE_M:
                d = math.inf
            yield Frame(
                episode=f"ep{e:02d}",
                step=t,
                sensors={name: make(d, rng) for name, make in (("rgb", _rgb), ("heightmap", _heightmap))
                         if name in modalities},
                meta={"terrain": "flat" if flat else "single_block", "obstacle_distance": d},
            )


def _cfg(root: Path, name: str = "run", **overrides: object) -> VaeConfig:
    settings: dict[str, object] = {
        "image_size": 32,
        "batch_size": 32,
        "epochs": 4,
        "out_dir": str(root / name / "model"),
        "report_dir": str(root / name / "report"),
        "data_dir": str(root / "rollouts"),
    }
    return VaeConfig(**(settings | overrides))


@pytest.fixture(autouse=True)
def _outside_any_repo(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # dvclive runs `dvc init` on the enclosing git repo when it finds no DVC repo; keep tests out of it.
    monkeypatch.chdir(tmp_path)


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> tuple[VaeConfig, dict[str, float]]:
    """One 4-epoch heightmap run shared by the end-to-end, export and determinism tests."""
    root = tmp_path_factory.mktemp("trained")
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(root)
        cfg = _cfg(root)
        return cfg, train_vae(cfg, synthetic_frames())


# ------------------------------------------------------------------------------------------------ model


@pytest.mark.parametrize(("channels", "size"), [(3, 64), (1, 64), (1, 32)])
def test_shapes(channels: int, size: int) -> None:
    model = ConvVAE(channels, size, latent_dim=8)
    with torch.no_grad():
        recon, mu, logvar = model(torch.rand(2, channels, size, size))
    assert recon.shape == (2, channels, size, size)
    assert mu.shape == logvar.shape == (2, 8)
    assert float(recon.min()) >= 0.0 and float(recon.max()) <= 1.0


def test_image_size_must_allow_four_halvings() -> None:
    with pytest.raises(ValueError, match="multiple of 16"):
        ConvVAE(1, 40)


def test_preprocess_rgb_resizes_and_scales() -> None:
    raw = np.full((2, 48, 48, 3), 255, np.uint8)
    raw[:, :, :, 1] = 0
    x = preprocess(raw, "rgb", 32)
    assert x.shape == (2, 3, 32, 32) and x.dtype == np.float32
    np.testing.assert_allclose(x[:, 0], 1.0)
    np.testing.assert_allclose(x[:, 1], 0.0)


def test_preprocess_heightmap_clips_to_documented_range() -> None:
    raw = np.array([[[-1.0, 0.0], [0.25, np.nan]]], np.float32)  # (1, 2, 2) metres
    x = preprocess(raw, "heightmap", 16)
    assert x.shape == (1, 1, 16, 16)
    corners = x[0, 0, [0, 0, -1, -1], [0, -1, 0, -1]]
    np.testing.assert_allclose(corners, [0.0, 0.375, 1.0, 0.0], atol=1e-6)  # nan -> low bound


def test_loss_decreases_on_tiny_set() -> None:
    """beta=0.1 so 60 steps get past the 'mean image' plateau a beta=1 VAE sits on early in training."""
    torch.manual_seed(0)
    rng = np.random.default_rng(0)
    raw = np.stack([_heightmap(d, rng) for d in np.linspace(0.0, 1.3, 32)])  # a block in view in each
    x = torch.from_numpy(preprocess(raw, "heightmap", 32))
    model = ConvVAE(1, 32)
    optimizer = torch.optim.Adam(model.parameters(), lr=3e-3)
    noise = torch.Generator().manual_seed(0)
    recon = [train_step(model, optimizer, x, 0.1, noise)[1] for _ in range(60)]
    assert np.mean(recon[-5:]) < 0.5 * np.mean(recon[:5])


def test_kl_is_zero_for_standard_normal_posterior() -> None:
    x = torch.rand(4, 1, 16, 16)
    loss = vae_loss(x, x, torch.zeros(4, 8), torch.zeros(4, 8))
    assert float(loss.kl) == pytest.approx(0.0) and float(loss.recon) == pytest.approx(0.0)


# ------------------------------------------------------------------------------------------------- data


def test_split_is_by_episode() -> None:
    data = build_dataset(synthetic_frames(episodes=10, steps=5), "heightmap", 32)
    train, val = split_by_episode(data, 0.2, seed=3)
    train_eps, val_eps = set(data.episode_index[train]), set(data.episode_index[val])
    assert not train_eps & val_eps
    assert len(val_eps) == 2 and len(train_eps) == 8
    assert sorted([*train, *val]) == list(range(len(data)))
    assert data.images.dtype == np.float16 and data.images.shape == (50, 1, 32, 32)


def test_split_is_seeded() -> None:
    data = build_dataset(synthetic_frames(episodes=10, steps=2), "heightmap", 32)
    a, b = split_by_episode(data, 0.3, seed=1), split_by_episode(data, 0.3, seed=1)
    assert all(np.array_equal(u, v) for u, v in zip(a, b, strict=True))


def _one_line(exc: pytest.ExceptionInfo[BaseException]) -> str:
    message = str(exc.value)
    assert "\n" not in message
    return message


def test_threads_honour_a_limit_and_omp_num_threads(monkeypatch: pytest.MonkeyPatch) -> None:
    """Two trainings that each take every core crawl; a sweep trial or OMP_NUM_THREADS caps them."""
    before = torch.get_num_threads()
    try:
        monkeypatch.setattr(stage.os, "sched_getaffinity", lambda _: {0, 1, 2, 3})
        monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
        assert stage.configure_threads() == 4 and stage.configure_threads(2) == 2 and stage.configure_threads(9) == 4
        monkeypatch.setenv("OMP_NUM_THREADS", "1")
        assert stage.configure_threads() == 1 and stage.configure_threads(3) == 3  # an explicit limit wins
        monkeypatch.setenv("OMP_NUM_THREADS", "many")  # not a number: OpenMP ignores it, and so do we
        assert stage.configure_threads() == 4
    finally:
        torch.set_num_threads(before)


def test_no_frames_is_a_clear_error() -> None:
    with pytest.raises(VaeDataError) as exc:
        build_dataset(iter(()), "heightmap", 32, source="data/rollouts")
    assert _one_line(exc) == "data/rollouts: no frames found (run the collect stage first)"


def test_missing_modality_names_what_is_there() -> None:
    with pytest.raises(VaeDataError) as exc:
        build_dataset(synthetic_frames(episodes=2, steps=2), "rgb", 32, source="data/rollouts")
    assert _one_line(exc) == "data/rollouts: no 'rgb' frames (rollouts contain: heightmap)"


def _write_rollouts(folder: Path, frames: Iterator[Frame]) -> None:
    """Log frames (height maps only) to one MCAP per episode with the real EpisodeWriter."""
    by_episode: dict[str, list[Frame]] = {}
    for frame in frames:
        by_episode.setdefault(frame.episode, []).append(frame)
    pose = (np.array([HM_NEAR, -0.8, 0.0]), np.array([0.0, 0.0, 0.0, 1.0]), 0.05)
    for episode, steps in by_episode.items():
        with EpisodeWriter(folder / f"{episode}.mcap", {"episode": {"terrain": "single_block"}}) as writer:
            for k, frame in enumerate(steps):
                writer.log_step(
                    (k + 1) * 50_000_000,
                    transforms=[],
                    sensors=[Message("/heightmap", "grid", (frame.sensors["heightmap"], pose), "heading")],
                    joints={},
                    cpg={},
                    step=frame.meta,
                )


def test_stage_reads_mcap_rollouts(tmp_path: Path) -> None:
    """Through the real reader: inf distances survive the JSON null, and a missing sensor is named."""
    folder = tmp_path / "rollouts"
    _write_rollouts(folder, synthetic_frames(episodes=4, steps=8))
    data = load_dataset(_cfg(tmp_path))
    assert len(data) == 32 and len(data.episodes) == 4
    assert np.isinf(data.obstacle_distance[data.episode_index == 3]).all()  # the flat episode
    with pytest.raises(VaeDataError) as exc:
        load_dataset(_cfg(tmp_path, modality="rgb"))
    assert _one_line(exc) == f"{folder}: no 'rgb' frames (rollouts contain: heightmap)"


def test_single_episode_cannot_be_split() -> None:
    with pytest.raises(VaeDataError) as exc:
        build_dataset(synthetic_frames(episodes=1, steps=3), "heightmap", 32, source="data/rollouts")
    assert "only one episode ('ep00')" in _one_line(exc)


def test_missing_data_dir(tmp_path: Path) -> None:
    with pytest.raises(VaeDataError) as exc:
        train_vae(_cfg(tmp_path))
    assert "rollouts: no such folder" in _one_line(exc)


def test_linear_probe_separable_and_baseline() -> None:
    rng = np.random.default_rng(0)
    x = rng.normal(size=(200, 3)).astype(np.float32)
    y = x[:, 0] + 0.1 * x[:, 1] > 0.5
    accuracy, baseline = linear_probe(x[:150], y[:150], x[150:], y[150:])
    assert accuracy > 0.95
    assert baseline == pytest.approx(max(y[150:].mean(), 1 - y[150:].mean()))
    assert all(math.isnan(v) for v in linear_probe(x, y, x[:0], y[:0]))  # no val frames of either class


def test_active_dims_counts_varying_latents() -> None:
    mu = np.zeros((100, 4), np.float32)
    mu[:, 1] = np.linspace(-1, 1, 100)  # informative
    mu[:, 2] = np.linspace(-0.01, 0.01, 100)  # collapsed: tiny spread
    assert active_dims(mu) == 1


# ----------------------------------------------------------------------------------------------- export


def test_export_roundtrip_matches_model_mu(tmp_path: Path) -> None:
    torch.manual_seed(0)
    model = ConvVAE(3, 32).eval()
    raw = np.stack([f.sensors["rgb"] for f in synthetic_frames(episodes=1, steps=6, modalities=("rgb",))])
    export_encoder(model, tmp_path, encoder_config(model, "rgb", raw.shape[1:]))
    encoder = load_encoder(tmp_path)
    assert (encoder.modality, encoder.latent_dim) == ("rgb", 8)
    with torch.no_grad():
        expected = model.encoder(torch.from_numpy(preprocess(raw, "rgb", 32)))[0].numpy()
    latents = encoder.encode(raw)
    assert latents.dtype == np.float32 and latents.shape == (6, 8)
    np.testing.assert_allclose(latents, expected, rtol=1e-5, atol=1e-5)
    assert not any(p.requires_grad for p in encoder._net.parameters())


def test_encoder_rejects_other_sensor_shape(tmp_path: Path) -> None:
    model = ConvVAE(1, 32)
    export_encoder(model, tmp_path, encoder_config(model, "heightmap", (32, 32)))
    with pytest.raises(EncoderError, match=r"trained on frames of shape \(32, 32\)"):
        load_encoder(tmp_path).encode(np.zeros((1, 16, 16), np.float32))


def test_load_encoder_missing_files_names_the_path(tmp_path: Path) -> None:
    with pytest.raises(EncoderError) as exc:
        load_encoder(tmp_path / "nowhere")
    assert str(tmp_path / "nowhere" / "encoder.json") in _one_line(exc)


# ------------------------------------------------------------------------------------------------ stage


def test_end_to_end_outputs(trained: tuple[VaeConfig, dict[str, float]]) -> None:
    cfg, metrics = trained
    report = Path(cfg.report_dir)
    summary = json.loads((report / "metrics.json").read_text())
    assert summary["val"]["loss"] == pytest.approx(metrics["val/loss"])
    speed = json.loads((report / "speed.json").read_text())
    assert speed["train"]["images_per_s"] > 0 and "images_per_s" not in summary["train"]  # timings apart
    assert speed["machine"]["torch_threads"] >= 1 and "machine" not in summary  # where it ran, beside the timings
    for name in ("recon_grid.png", "latent_map.png"):
        assert (report / "plots" / "images" / name).stat().st_size > 1000
    for name in ("train/recon", "train/kl", "train/loss", "val/recon", "val/kl", "val/loss"):
        assert len((report / "plots" / "metrics" / f"{name}.tsv").read_text().splitlines()) == 1 + cfg.epochs
    assert not (report / "dvc.yaml").exists()
    assert metrics["probe_accuracy"] >= metrics["probe_baseline"] + 0.2
    assert 0 <= summary["latent"]["active_dims"] <= cfg.latent_dim


def test_exported_files_load_with_weights_only(trained: tuple[VaeConfig, dict[str, float]]) -> None:
    cfg, _ = trained
    out = Path(cfg.out_dir)
    state = torch.load(out / "encoder.pt", weights_only=True)
    assert all(key.startswith(("conv.", "head.")) for key in state)
    assert torch.load(out / "checkpoint.pt", weights_only=True)["epoch"] == cfg.epochs
    config = json.loads((out / "encoder.json").read_text())
    assert config["input_shape"] == [32, 32]
    assert config["normalisation"] == {"low": -0.15, "high": 0.25, "units": "m"}
    frames = list(synthetic_frames(episodes=1, steps=4, seed=7))
    latents = load_encoder(out).encode(np.stack([f.sensors["heightmap"] for f in frames]))
    assert latents.shape == (4, cfg.latent_dim) and np.isfinite(latents).all()


def test_same_seed_same_result(tmp_path: Path, trained: tuple[VaeConfig, dict[str, float]]) -> None:
    _, reference = trained
    metrics = train_vae(_cfg(tmp_path), synthetic_frames())
    assert metrics["train/loss"] == reference["train/loss"]
    assert metrics["val/loss"] == reference["val/loss"]


def _count_train_steps(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Wrap the stage's train_step; the returned list grows by one per optimiser step."""
    calls: list[int] = []

    def counting(*args: Any) -> tuple[float, float, float]:
        calls.append(1)
        return train_step(*args)

    monkeypatch.setattr(stage, "train_step", counting)
    return calls


def test_resume_continues_at_next_epoch(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, trained: tuple[VaeConfig, dict[str, float]]
) -> None:
    _, reference = trained
    train_vae(_cfg(tmp_path, epochs=2), synthetic_frames())
    calls = _count_train_steps(monkeypatch)
    cfg = _cfg(tmp_path, epochs=4)
    metrics = train_vae(cfg, synthetic_frames())
    batches_per_epoch = math.ceil(10 * 20 / cfg.batch_size)  # 10 of 12 episodes train, 20 frames each
    assert len(calls) == 2 * batches_per_epoch  # epochs 3 and 4 only
    assert metrics["val/loss"] == reference["val/loss"]  # identical to the uninterrupted run
    val_curve = (Path(cfg.report_dir) / "plots" / "metrics" / "val" / "loss.tsv").read_text().splitlines()
    assert len(val_curve) == 1 + 4


def test_changed_settings_start_fresh(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    train_vae(_cfg(tmp_path, epochs=1), synthetic_frames(episodes=4, steps=8))
    calls = _count_train_steps(monkeypatch)
    train_vae(_cfg(tmp_path, epochs=1, beta=0.5), synthetic_frames(episodes=4, steps=8))
    assert calls  # a checkpoint from other settings is not resumed


def test_a_checkpoint_from_other_code_starts_fresh(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    train_vae(_cfg(tmp_path, epochs=1), synthetic_frames(episodes=4, steps=8))
    calls = _count_train_steps(monkeypatch)
    monkeypatch.setattr(stage, "code_fingerprint", lambda: "edited-code")
    train_vae(_cfg(tmp_path, epochs=1), synthetic_frames(episodes=4, steps=8))
    assert calls  # same settings and data, but made by other code: not resumed
