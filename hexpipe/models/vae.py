"""Convolutional VAE over the terrain sensor, its loss, the shared preprocessing, and the frozen encoder.

The VAE compresses what the robot sees ahead (an RGB camera frame or a height map) into a small latent whose
posterior mean is the terrain embedding PPO consumes. Everything the policy side needs at run time lives here
(`preprocess`, `load_encoder`); the training stage is `hexpipe.models.train_vae`.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import torch
from torch import Tensor, nn

from hexpipe import sensors as registry
from hexpipe.atomic import write_text
from hexpipe.models.weights import WeightsError, load_state_dict, save_state_dict

ENCODER_WEIGHTS = "encoder.pt"
ENCODER_CONFIG = "encoder.json"
RISE_HEAD_WEIGHTS = "rise_head.pt"  # the training-only rise head, exported for ppo.rise_readout
RISE_HEAD_OUTPUTS = "rise_head_outputs"  # encoder.json key: the head's output count (0: none exported)
ENCODER_FORMAT_VERSION = 1

# Encoder widths of the 4 stride-2 conv layers; the decoder mirrors them. 32-64-64-128 trained at only ~410-470
# images/s at 64x64 on 2 CPU cores, dominated by the 32->64 layer at 16x16 and its mirror; 32-32-64-128 keeps
# 32 channels at full resolution and the deep width, at ~1.65x the speed (see benchmarks/bench_vae.py).
DEFAULT_CHANNELS: tuple[int, int, int, int] = (32, 32, 64, 128)

HEIGHTMAP_RANGE_M = registry.get("heightmap").image.low, registry.get("heightmap").image.high  # m (the sensor's)


class EncoderError(ValueError):
    """A missing or inconsistent exported encoder, or an input it cannot encode; one line naming the cause."""


@dataclass(frozen=True)
class Normalisation:
    """Affine map of a raw sensor value to [0, 1]: clip((x - low) / (high - low), 0, 1).

    Each image sensor declares its window (`hexpipe.sensors`, `ImagePrep`): rgb 0..255 (uint8 intensity),
    heightmap HEIGHTMAP_RANGE_M (metres; non-finite cells, no ray hit, are treated as `low`).
    """

    low: float
    high: float
    units: str

    @classmethod
    def for_modality(cls, modality: str) -> Normalisation:
        prep = _prep(modality)
        return cls(prep.low, prep.high, prep.units)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _prep(modality: str) -> registry.ImagePrep:
    prep = registry.get(modality).image
    if prep is None:
        raise ValueError(f"sensor {modality!r} is not an image the VAE can encode; use one of "
                         f"{', '.join(registry.image_sensors())}")
    return prep


def channels_for(modality: str) -> int:
    """Input channels of the VAE for a sensor: 3 for rgb, 1 for a height map."""
    return _prep(modality).channels


def preprocess(raw: np.ndarray, modality: str, image_size: int, norm: Normalisation | None = None) -> np.ndarray:
    """Raw sensor batch -> float32 (N, C, image_size, image_size) in [0, 1]; used by training and encoder.

    rgb: (N, H, W, 3) uint8. heightmap: (N, R, C) float metres (`ImagePrep.describe`). Values are normalised
    (and clipped) first, then resized with cv2.INTER_AREA, so a clipped spike cannot bleed into its neighbours.
    """
    prep = _prep(modality)
    norm = norm or Normalisation.for_modality(modality)
    raw = np.asarray(raw)
    if raw.ndim != (4 if prep.channels_last else 3) or (prep.channels_last and raw.shape[-1] != prep.channels):
        raise ValueError(f"{modality} batch must be {prep.describe()}, got shape {raw.shape}")
    x = raw.astype(np.float32)
    if prep.nonfinite_to_low:
        x = np.nan_to_num(x, nan=norm.low, posinf=norm.high, neginf=norm.low)
    x = np.clip((x - norm.low) / (norm.high - norm.low), 0.0, 1.0)
    if x.shape[1:3] != (image_size, image_size):
        size = (image_size, image_size)
        x = np.stack([cv2.resize(img, size, interpolation=cv2.INTER_AREA) for img in x])
    if prep.channels_last:
        return np.ascontiguousarray(x.transpose(0, 3, 1, 2))
    return x[:, None]


def _check_image_size(image_size: int) -> None:
    if image_size < 16 or image_size % 16:
        raise ValueError(f"image_size must be a multiple of 16 (4 stride-2 layers), got {image_size}")


class ConvEncoder(nn.Module):
    """4 stride-2 convs (image_size -> image_size/16) and a linear head to (mu, logvar)."""

    def __init__(
        self,
        in_channels: int,
        image_size: int = 64,
        latent_dim: int = 8,
        channels: Sequence[int] = DEFAULT_CHANNELS,
    ) -> None:
        super().__init__()
        _check_image_size(image_size)
        layers: list[nn.Module] = []
        prev = in_channels
        for width in channels:
            layers += [nn.Conv2d(prev, width, kernel_size=4, stride=2, padding=1), nn.ReLU(inplace=True)]
            prev = width
        self.conv = nn.Sequential(*layers, nn.Flatten())
        self.head = nn.Linear(prev * (image_size // 16) ** 2, 2 * latent_dim)
        self.latent_dim = latent_dim

    def forward(self, x: Tensor) -> tuple[Tensor, Tensor]:
        mu, logvar = self.head(self.conv(x)).chunk(2, dim=1)
        # Bounded log-variance keeps exp() finite early in training; the bound (std in [7e-3, 150]) never
        # binds at a sensible optimum.
        return mu, logvar.clamp(-10.0, 10.0)


class ConvDecoder(nn.Module):
    """Mirror of ConvEncoder: linear to a (C, s/16, s/16) map, 4 stride-2 transposed convs, sigmoid."""

    def __init__(
        self,
        out_channels: int,
        image_size: int = 64,
        latent_dim: int = 8,
        channels: Sequence[int] = DEFAULT_CHANNELS,
    ) -> None:
        super().__init__()
        _check_image_size(image_size)
        widths = list(channels)[::-1]
        self.start = (widths[0], image_size // 16, image_size // 16)
        self.fc = nn.Linear(latent_dim, widths[0] * (image_size // 16) ** 2)
        layers: list[nn.Module] = [nn.ReLU(inplace=True)]
        for prev, width in zip(widths, [*widths[1:], out_channels], strict=True):
            layers += [
                nn.ConvTranspose2d(prev, width, kernel_size=4, stride=2, padding=1),
                nn.ReLU(inplace=True),
            ]
        layers[-1] = nn.Sigmoid()
        self.deconv = nn.Sequential(*layers)

    def forward(self, z: Tensor) -> Tensor:
        return self.deconv(self.fc(z).view(-1, *self.start))


class ConvVAE(nn.Module):
    """VAE over (N, in_channels, image_size, image_size) inputs in [0, 1]; Gaussian latent of latent_dim."""

    def __init__(
        self,
        in_channels: int,
        image_size: int = 64,
        latent_dim: int = 8,
        channels: Sequence[int] = DEFAULT_CHANNELS,
    ) -> None:
        super().__init__()
        self.in_channels = in_channels
        self.image_size = image_size
        self.latent_dim = latent_dim
        self.channels = tuple(channels)
        self.encoder = ConvEncoder(in_channels, image_size, latent_dim, channels)
        self.decoder = ConvDecoder(in_channels, image_size, latent_dim, channels)

    def forward(self, x: Tensor, generator: torch.Generator | None = None) -> tuple[Tensor, Tensor, Tensor]:
        """Returns (reconstruction, mu, logvar); z is sampled with `generator` for reproducibility."""
        mu, logvar = self.encoder(x)
        eps = torch.randn(mu.shape, generator=generator, dtype=mu.dtype, device=mu.device)
        z = mu + eps * torch.exp(0.5 * logvar)
        return self.decoder(z), mu, logvar


@dataclass(frozen=True)
class VaeLoss:
    """Per-image loss terms, averaged over the batch (nats for KL; squared [0,1] units summed over pixels)."""

    total: Tensor
    recon: Tensor
    kl: Tensor


def vae_loss(recon: Tensor, x: Tensor, mu: Tensor, logvar: Tensor, beta: float = 1.0) -> VaeLoss:
    """Summed squared error per image + beta * KL(q(z|x) || N(0, I)), both averaged over the batch.

    Squared error rather than Bernoulli because inputs are continuous intensities / heights, not binary: the
    Bernoulli likelihood has a non-zero, input-dependent floor on such targets, so its recon figure is not
    comparable across data. The summed squared error is the Gaussian NLL with variance 1/2 (up to a constant),
    so beta=1 is the ELBO of that model and the recon/KL balance is independent of the batch size.
    """
    n = x.shape[0]
    recon_term = (recon - x).pow(2).sum() / n
    kl_term = -0.5 * (1.0 + logvar - mu.pow(2) - logvar.exp()).sum() / n
    return VaeLoss(recon_term + beta * kl_term, recon_term, kl_term)


def encoder_config(model: ConvVAE, modality: str, input_shape: Sequence[int], **extra: Any) -> dict[str, Any]:
    """The JSON written beside encoder.pt: everything needed to rebuild the encoder and feed it raw arrays."""
    return {
        "format_version": ENCODER_FORMAT_VERSION,
        "modality": modality,
        "in_channels": model.in_channels,
        "image_size": model.image_size,
        "latent_dim": model.latent_dim,
        "channels": list(model.channels),
        "normalisation": Normalisation.for_modality(modality).to_dict(),
        "input_shape": [int(s) for s in input_shape],  # one raw frame as logged: (H, W, 3) or (R, C)
        **extra,
    }


def export_encoder(model: ConvVAE, out_dir: str | Path, config: dict[str, Any], head: nn.Linear | None = None) -> None:
    """Write <out_dir>/encoder.pt (encoder state_dict only) and encoder.json, each atomically, and the rise head
    as rise_head.pt (or remove an older one: a head must never outlive the encoder it was trained with)."""
    out = Path(out_dir)
    if head is None:
        (out / RISE_HEAD_WEIGHTS).unlink(missing_ok=True)
    else:
        save_state_dict(head.state_dict(), out / RISE_HEAD_WEIGHTS)
    save_state_dict(model.encoder.state_dict(), out / ENCODER_WEIGHTS)
    write_text(out / ENCODER_CONFIG, json.dumps({**config, RISE_HEAD_OUTPUTS: 0 if head is None else head.out_features},
                                                indent=2) + "\n")


class FrozenEncoder:
    """The trained encoder for inference: raw sensor arrays in, posterior means out; never trains.

    With a `readout` (the VAE's rise head, `load_encoder(..., rise_readout=True)`) each embedding is the mean
    followed by the head's outputs: the predicted distance to the next rise and its height (standardised), the
    logit of "a rise in range" (and, with vae.profile_weight, the band heights). `latent_dim` is then the length
    of that whole embedding, which is what the policy's input counts.
    """

    def __init__(self, encoder: ConvEncoder, config: dict[str, Any], readout: nn.Linear | None = None) -> None:
        self._net = encoder.eval().requires_grad_(False)
        self._readout = None if readout is None else readout.eval().requires_grad_(False)
        self.config = config
        self.modality: str = config["modality"]
        self.latent_dim: int = int(config["latent_dim"]) + (0 if readout is None else readout.out_features)
        self.image_size: int = int(config["image_size"])
        self.input_shape: tuple[int, ...] = tuple(config["input_shape"])
        self.normalisation = Normalisation(**config["normalisation"])

    def encode(self, batch: np.ndarray) -> np.ndarray:
        """(N, H, W, 3) uint8 or (N, R, C) float32 -> (N, latent_dim) float32 posterior means."""
        batch = np.asarray(batch)
        if batch.shape[1:] != self.input_shape:
            raise EncoderError(
                f"{self.modality} encoder was trained on frames of shape {self.input_shape}, got batch "
                f"{batch.shape}; match the sensor config or retrain the VAE"
            )
        dtype = _prep(self.modality).dtype
        if dtype is not None and batch.dtype != np.dtype(dtype):
            raise EncoderError(f"{self.modality} encoder expects {dtype} frames, got {batch.dtype}")
        x = preprocess(batch, self.modality, self.image_size, self.normalisation)
        with torch.inference_mode():
            mu, _ = self._net(torch.from_numpy(x))
            if self._readout is not None:
                mu = torch.cat([mu, self._readout(mu)], dim=1)
        return mu.numpy().astype(np.float32, copy=False)


def load_encoder(directory: str | Path, rise_readout: bool = False) -> FrozenEncoder:
    """Rebuild the exported encoder from <directory>/encoder.{pt,json}, in eval mode with gradients off;
    rise_readout: append the rise head's outputs (<directory>/rise_head.pt) to each embedding."""
    directory = Path(directory)
    weights, cfg_path = directory / ENCODER_WEIGHTS, directory / ENCODER_CONFIG
    for path in (cfg_path, weights):
        if not path.is_file():
            raise EncoderError(f"encoder file not found: {path} (run the train_vae stage first)")
    try:
        config = json.loads(cfg_path.read_text())
        encoder = ConvEncoder(
            int(config["in_channels"]),
            int(config["image_size"]),
            int(config["latent_dim"]),
            tuple(config["channels"]),
        )
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
        raise EncoderError(f"{cfg_path}: unreadable encoder config ({_first_line(exc)})") from None
    try:
        encoder.load_state_dict(load_state_dict(weights))  # weights only: a crafted file cannot run code
    except WeightsError as exc:
        raise EncoderError(str(exc)) from None
    except RuntimeError as exc:  # missing keys or other shapes
        raise EncoderError(f"{weights}: does not match {cfg_path} ({_first_line(exc)})") from None
    readout = _load_readout(directory, config) if rise_readout else None
    try:
        return FrozenEncoder(encoder, config, readout)
    except (KeyError, TypeError, ValueError) as exc:
        raise EncoderError(f"{cfg_path}: unreadable encoder config ({_first_line(exc)})") from None


def _load_readout(directory: Path, config: dict[str, Any]) -> nn.Linear:
    """The rise head train-vae exported beside the encoder, as a frozen Linear(latent_dim, outputs)."""
    outputs = int(config.get(RISE_HEAD_OUTPUTS) or 0)
    path = directory / RISE_HEAD_WEIGHTS
    if outputs <= 0 or not path.is_file():
        raise EncoderError(f"{directory}: no rise head beside the encoder ({path.name}; train the VAE with "
                           "vae.feature_weight > 0), which ppo.rise_readout reads")
    head = nn.Linear(int(config["latent_dim"]), outputs)
    try:
        head.load_state_dict(load_state_dict(path))
    except WeightsError as exc:
        raise EncoderError(str(exc)) from None
    except RuntimeError as exc:
        raise EncoderError(f"{path}: does not match {ENCODER_CONFIG} ({_first_line(exc)})") from None
    return head


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__
