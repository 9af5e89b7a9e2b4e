"""Training-only auxiliary head: the VAE's latent mean -> the next rise's distance and height, and "rise in range".

Why: a plain VAE spends its 8 dims on reconstruction. The rise ahead is in the latent but not linearly (ridge R²
0.55 for its distance and 0.04 for its height on the 100-episode pilot data, kNN 0.83 and 0.64), while the gait needs
it readable. A linear head on mu, trained with the VAE at weight `vae.feature_weight`, pulls these quantities onto
linear directions of the latent. The frozen encoder still returns the 8-d mean; train-vae exports the head beside it
(rise_head.pt), and a policy with ppo.rise_readout reads the head's predictions after the mean.

With `vae.profile_weight` > 0 the head also predicts the terrain profile: the highest cell in each of
`vae.profile_bands` equal bands of the map's rows, across the legs' corridor. Why: the rise targets are all ahead,
and the latent carried the band under the hind feet worst (reports/experiments/band_probe.py), while a policy that
lowers its feet with its hind legs still on a block gets stuck there (reports/experiments/collapse_trace.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise

import numpy as np
import torch
from torch import Tensor, nn
from torch.nn.functional import binary_cross_entropy_with_logits


@dataclass(frozen=True)
class RiseScale:
    """Standardisation of the regression targets (metres), fitted on the training frames with a rise in range, so
    that distance (~0-1.4 m) and height (~0.02-0.12 m) weigh alike in the loss."""

    distance_mean: float
    distance_std: float
    height_mean: float
    height_std: float

    @classmethod
    def fit(cls, distance: np.ndarray, height: np.ndarray) -> RiseScale:
        """From the (N,) labels of `VaeDataset` (inf or nan where undefined); mean 0, std 1 where nothing is."""

        def stats(y: np.ndarray) -> tuple[float, float]:
            y = y[np.isfinite(y)]
            return (float(y.mean()), float(y.std()) + 1e-6) if len(y) else (0.0, 1.0)

        return cls(*stats(distance), *stats(height))


def rise_targets(distance: np.ndarray, height: np.ndarray, scale: RiseScale) -> Tensor:
    """(N, 3) float32 targets: standardised distance, standardised height, rise in range (1/0).

    NaN marks what is undefined and is masked out by `rise_loss`: distance and height on frames with no rise in
    range (distance inf), all three on frames recorded before the labels existed (distance nan).
    """
    distance = np.asarray(distance, np.float64)
    height = np.asarray(height, np.float64)
    in_range = np.where(np.isnan(distance), np.nan, np.isfinite(distance).astype(np.float64))
    with np.errstate(invalid="ignore"):  # inf - mean on frames with nothing ahead: masked as non-finite below
        d = (distance - scale.distance_mean) / scale.distance_std
    h = (height - scale.height_mean) / scale.height_std
    out = np.stack([d, h, in_range], axis=1)
    out[~np.isfinite(out)] = np.nan
    return torch.from_numpy(out.astype(np.float32))


def terrain_profile(images: np.ndarray, bands: int, corridor: float) -> np.ndarray:
    """(N, bands) float32: the highest value of each band of image rows (bands from the map's near edge, behind the
    base, to its far edge) across the central `corridor` fraction of the columns, from preprocessed height maps
    (N, 1, S, S) in [0, 1] (rows run forward, as the height-map sensor's)."""
    images = np.asarray(images)
    size, cols = images.shape[-2], images.shape[-1]
    keep = max(1, round(corridor * cols))
    first = (cols - keep) // 2
    strip = images[:, 0, :, first : first + keep].max(axis=-1).astype(np.float32)  # (N, rows)
    edges = np.linspace(0, size, bands + 1).round().astype(int)
    return np.stack([strip[:, a:b].max(axis=1) for a, b in pairwise(edges)], axis=1)


def standardise(values: np.ndarray, fit_on: np.ndarray) -> Tensor:
    """(N, K) values standardised per column with the mean and std of the rows `fit_on` (the training frames)."""
    mean, std = values[fit_on].mean(axis=0), values[fit_on].std(axis=0) + 1e-6
    return torch.from_numpy(((values - mean) / std).astype(np.float32))


class RiseHead(nn.Linear):
    """Linear map latent mean -> (distance, height, in-range logit, then `profile_bands` band heights): linear,
    because a linear read-out is what the ridge probes measure and what the policy's first layer sees."""

    def __init__(self, latent_dim: int, profile_bands: int = 0) -> None:
        super().__init__(latent_dim, 3 + profile_bands)


def rise_loss(predicted: Tensor, targets: Tensor) -> Tensor:
    """Masked squared error on the standardised distance and height plus BCE on "rise in range", summed per image
    and averaged over the batch (as `vae_loss`); undefined (NaN) targets contribute exactly 0, gradient included."""
    mask = torch.isfinite(targets)
    clean = torch.where(mask, targets, torch.zeros_like(targets))
    squared = (predicted[:, :2] - clean[:, :2]).pow(2)
    bce = binary_cross_entropy_with_logits(predicted[:, 2], clean[:, 2], reduction="none")
    per_frame = torch.where(mask[:, :2], squared, 0.0).sum(1) + torch.where(mask[:, 2], bce, 0.0)
    return per_frame.sum() / max(1, len(targets))


def profile_loss(predicted: Tensor, targets: Tensor) -> Tensor:
    """Squared error on the standardised band heights, summed per image and averaged over the batch: each band
    weighs as much as the rise's distance or height."""
    return (predicted - targets).pow(2).sum() / max(1, len(targets))


__all__ = ["RiseHead", "RiseScale", "profile_loss", "rise_loss", "rise_targets", "standardise", "terrain_profile"]
