"""The VAE's training-only aux head (vae.feature_weight): masked targets and loss, the plain VAE at weight 0, and a
tiny train_vae run in which the head makes the latent carry the rise ahead linearly."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import torch
from test_probes import frames

from hexpipe.config import ConfigError, VaeConfig, load_params
from hexpipe.models.rise_head import RiseHead, RiseScale, rise_loss, rise_targets, terrain_profile
from hexpipe.models.train_vae import objective, train_step, train_vae
from hexpipe.models.vae import ConvVAE
from hexpipe.models.vae_data import build_dataset

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(autouse=True)
def _outside_any_repo(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # dvclive would `dvc init` the enclosing git repo


def test_targets_mark_what_is_undefined() -> None:
    distance = np.array([0.5, 1.0, np.inf, np.nan], np.float32)  # rise, rise, nothing in range, unlabelled
    height = np.array([0.05, 0.10, np.nan, np.nan], np.float32)
    scale = RiseScale.fit(distance, height)
    assert scale.distance_mean == pytest.approx(0.75) and scale.height_mean == pytest.approx(0.075)
    t = rise_targets(distance, height, scale).numpy()
    np.testing.assert_allclose(t[:2, :2], [[-1.0, -1.0], [1.0, 1.0]], atol=1e-4)
    np.testing.assert_array_equal(t[:, 2][:3], [1.0, 1.0, 0.0])
    assert np.isnan(t[2, :2]).all() and np.isnan(t[3]).all()


def test_loss_masks_frames_without_a_rise() -> None:
    """NaN targets add exactly nothing, to the loss or to the gradient: the loss over a batch with unlabelled and
    rise-less frames is the loss over the labelled part, rescaled to the batch size."""
    torch.manual_seed(0)
    predicted = torch.randn(4, 3, requires_grad=True)
    targets = torch.tensor([[0.3, -0.2, 1.0], [1.1, 0.4, 1.0], [math.nan, math.nan, 0.0], [math.nan] * 3])
    loss = rise_loss(predicted, targets)
    loss.backward()
    assert torch.isfinite(loss) and torch.isfinite(predicted.grad).all()
    assert (predicted.grad[3] == 0).all() and (predicted.grad[2, :2] == 0).all() and predicted.grad[2, 2] != 0
    labelled = rise_loss(predicted[:2].detach(), targets[:2]) * 2
    in_range_only = torch.nn.functional.binary_cross_entropy_with_logits(predicted[2, 2].detach(), torch.tensor(0.0))
    assert loss.item() * 4 == pytest.approx(float(labelled + in_range_only), rel=1e-6)


def test_weight_zero_is_exactly_the_plain_vae_loss() -> None:
    torch.manual_seed(0)
    model, head = ConvVAE(1, 32), RiseHead(8)
    x = torch.rand(6, 1, 32, 32)
    targets = torch.tensor([[0.5, 0.1, 1.0]] * 3 + [[math.nan, math.nan, 0.0]] * 3)
    plain = objective(model, x, 0.25, torch.Generator().manual_seed(1))
    zero = objective(model, x, 0.25, torch.Generator().manual_seed(1), head, targets, 0.0)
    weighted = objective(model, x, 0.25, torch.Generator().manual_seed(1), head, targets, 2.0)
    assert zero[0].item() == plain[0].item() and zero[3].item() == 0.0
    assert weighted[0].item() == pytest.approx(plain[0].item() + 2.0 * weighted[3].item())
    assert weighted[3].item() > 0 and torch.isfinite(weighted[0])


def test_train_step_fits_the_head_through_the_encoder() -> None:
    """60 steps on one batch: the rise loss (masked rows included) falls below 60% of its start, so the head's
    gradient is applied and reaches the latent."""
    torch.manual_seed(0)
    data = build_dataset(frames("heightmap", episodes=2), "heightmap", 16)  # 48 frames, a third with no rise
    targets = rise_targets(data.rise_distance, data.rise_height, RiseScale.fit(data.rise_distance, data.rise_height))
    model, head = ConvVAE(1, 16), RiseHead(8)
    optimizer = torch.optim.Adam([*model.parameters(), *head.parameters()], lr=3e-3)
    noise, x = torch.Generator().manual_seed(0), data.batch(np.arange(len(data)))
    rise = [train_step(model, optimizer, x, 0.25, noise, head, targets, 5.0)[3] for _ in range(60)]
    assert all(math.isfinite(r) for r in rise) and np.mean(rise[-5:]) < 0.6 * np.mean(rise[:5])


def _cfg(root: Path, name: str, **overrides: object) -> VaeConfig:
    settings: dict[str, object] = {"image_size": 16, "batch_size": 32, "epochs": 4, "val_fraction": 0.5,
                                   "out_dir": str(root / name / "m"), "report_dir": str(root / name / "r"),
                                   "data_dir": str(root / "none")}
    return VaeConfig(**(settings | overrides))


def test_the_head_makes_the_rise_linearly_readable(tmp_path: Path) -> None:
    """Same data, seed and epochs (6 held-out episodes): with the head, its loss falls over the epochs and the ridge
    probes of the rise's distance and height on held-out episodes beat the plain VAE's (were the head's gradient
    lost, the two runs would train the same encoder bit for bit). Without a head there is no rise loss."""
    plain = train_vae(_cfg(tmp_path, "plain", feature_weight=0.0), frames("heightmap", episodes=12))
    aux_cfg = _cfg(tmp_path, "aux", feature_weight=5.0)
    aux = train_vae(aux_cfg, frames("heightmap", episodes=12))
    assert "val/rise" not in plain and math.isfinite(aux["val/rise"])
    curve = (Path(aux_cfg.report_dir) / "plots" / "metrics" / "train" / "rise.tsv").read_text().splitlines()[1:]
    rise = [float(line.split("\t")[-1]) for line in curve]
    assert len(rise) == 4 and rise[-1] < 0.95 * rise[0]
    for name in ("rise_distance_r2", "rise_height_r2"):
        assert aux[f"probe/{name}"] > plain[f"probe/{name}"], name
    saved = json.loads((Path(aux_cfg.out_dir) / "encoder.json").read_text())
    assert saved["latent_dim"] == 8 and saved["rise_head_outputs"] == 3  # the encoder as before; the head beside it
    state = torch.load(Path(aux_cfg.out_dir) / "encoder.pt", weights_only=True)
    assert all(key.startswith(("conv.", "head.")) for key in state)  # the encoder's own head (mu, logvar) only


def test_the_rise_readout_appends_the_heads_predictions(tmp_path: Path) -> None:
    """ppo.rise_readout: the embedding is the latent mean, then the exported head applied to it; an encoder trained
    without a head (feature_weight 0) has none to read, and says so in one line. A retrain without a head removes
    the old one, so a head never outlives its encoder."""
    from hexpipe.models.vae import EncoderError, load_encoder

    aux_cfg = _cfg(tmp_path, "aux", feature_weight=2.0, epochs=1)
    train_vae(aux_cfg, frames("heightmap", episodes=6))
    out = Path(aux_cfg.out_dir)
    batch = np.stack([f.sensors["heightmap"] for f in frames("heightmap", episodes=1)])
    plain, read = load_encoder(out).encode(batch), load_encoder(out, rise_readout=True)
    assert read.latent_dim == 11
    embedded = read.encode(batch)
    head = torch.load(out / "rise_head.pt", weights_only=True)
    expected = plain @ head["weight"].numpy().T + head["bias"].numpy()
    np.testing.assert_array_equal(embedded[:, :8], plain)
    np.testing.assert_allclose(embedded[:, 8:], expected, rtol=1e-5, atol=1e-6)

    train_vae(_cfg(tmp_path, "aux", feature_weight=0.0, epochs=1), frames("heightmap", episodes=6))
    assert not (out / "rise_head.pt").exists()
    with pytest.raises(EncoderError) as err:
        load_encoder(out, rise_readout=True)
    assert "no rise head" in str(err.value) and "vae.feature_weight > 0" in str(err.value)
    assert "\n" not in str(err.value)


def test_resume_restores_the_head(tmp_path: Path) -> None:
    """An interrupted run (2 then 3 epochs) ends where the uninterrupted one does, head and its optimiser state
    included; a checkpoint made at another feature_weight is not resumed."""
    whole = train_vae(_cfg(tmp_path, "whole", epochs=3, feature_weight=2.0), frames("heightmap", episodes=6))
    train_vae(_cfg(tmp_path, "parts", epochs=2, feature_weight=2.0), frames("heightmap", episodes=6))
    resumed = train_vae(_cfg(tmp_path, "parts", epochs=3, feature_weight=2.0), frames("heightmap", episodes=6))
    assert resumed["val/rise"] == whole["val/rise"] and resumed["val/loss"] == whole["val/loss"]
    other = train_vae(_cfg(tmp_path, "parts", epochs=3, feature_weight=1.0), frames("heightmap", episodes=6))
    assert other["val/loss"] != whole["val/loss"]


def test_config_rejects_a_negative_weight() -> None:
    with pytest.raises(ConfigError) as err:
        load_params(ROOT / "params.yaml", ["vae.feature_weight=-0.5"])
    assert "vae.feature_weight" in str(err.value) and "\n" not in str(err.value)


def test_terrain_profile_is_the_corridor_maximum_per_band() -> None:
    image = np.zeros((1, 1, 8, 8), np.float32)
    image[0, 0, 1, 3] = 0.5  # band 0 (rows 0-1), inside the central half (columns 2-5)
    image[0, 0, 6, 0] = 0.75  # band 3, outside the corridor: ignored
    image[0, 0, 7, 4] = 0.25  # band 3, inside
    np.testing.assert_array_equal(terrain_profile(image, bands=4, corridor=0.5), [[0.5, 0.0, 0.0, 0.25]])
    np.testing.assert_array_equal(terrain_profile(image, bands=4, corridor=1.0), [[0.5, 0.0, 0.0, 0.75]])


def test_profile_weight_zero_is_exactly_the_rise_head() -> None:
    """A profile head's extra outputs at profile_weight 0 change nothing; at a weight they add their loss."""
    torch.manual_seed(0)
    model, head = ConvVAE(1, 32), RiseHead(8, profile_bands=4)
    x = torch.rand(6, 1, 32, 32)
    targets = torch.cat([torch.tensor([[0.5, 0.1, 1.0]] * 6), torch.randn(6, 4)], dim=1)
    rise_only = objective(model, x, 0.25, torch.Generator().manual_seed(1), head, targets, 1.0)
    zero = objective(model, x, 0.25, torch.Generator().manual_seed(1), head, targets, 1.0, 0.0)
    both = objective(model, x, 0.25, torch.Generator().manual_seed(1), head, targets, 1.0, 2.0)
    assert zero[0].item() == rise_only[0].item() and zero[3].item() == rise_only[3].item()
    profile = both[3].item() - rise_only[3].item()
    assert profile > 0 and both[0].item() == pytest.approx(rise_only[0].item() + 2.0 * profile, rel=1e-6)


def test_the_profile_head_makes_the_rear_of_the_map_readable(tmp_path: Path) -> None:
    """Frames whose block sits at the map's near edge (behind the base) as often as ahead: with the profile head the
    latent's ridge R² for the rear band beats the rise head alone's, and every band is reported."""
    def rear_frames():
        rng = np.random.default_rng(3)
        for frame in frames("heightmap", episodes=12):
            hm = frame.sensors["heightmap"].copy()
            hm[:8] += rng.choice([0.0, rng.uniform(0.04, 0.12)])  # a block under the hind feet, or none
            yield frame.__class__(frame.episode, frame.step, {"heightmap": hm}, frame.meta)

    rise = train_vae(_cfg(tmp_path, "rise", feature_weight=1.0, profile_bands=4), rear_frames())
    profile = train_vae(_cfg(tmp_path, "profile", feature_weight=1.0, profile_bands=4, profile_weight=5.0),
                        rear_frames())
    assert {f"probe/profile_r2/band{k}" for k in range(4)} <= set(profile)
    assert profile["probe/profile_r2/band0"] > rise["probe/profile_r2/band0"]
    assert math.isfinite(profile["val/rise"]) and profile["val/rise"] > 0


def test_config_rejects_a_profile_without_height_maps() -> None:
    with pytest.raises(ConfigError) as err:
        load_params(ROOT / "params.yaml", ["vae.profile_weight=1", "vae.modality=rgb"])
    assert "profile_weight needs modality heightmap" in str(err.value) and "\n" not in str(err.value)
