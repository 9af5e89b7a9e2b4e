"""Training-only auxiliary head: the VAE's latent mean -> the next rise's distance and height, and "rise in range".

Why: a plain VAE spends its 8 dims on reconstruction. The rise ahead is in the latent but not linearly (ridge R²
0.55 for its distance and 0.04 for its height on the 100-episode pilot data, kNN 0.83 and 0.64), while the gait needs
it readable. A linear head on mu, trained with the VAE at weight `vae.feature_weight`, pulls these quantities onto
linear directions of the latent. The head is not exported: the frozen encoder still returns the 8-d mean.
"""

from __future__ import annotations

from dataclasses import dataclass

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


class RiseHead(nn.Linear):
    """Linear map latent mean -> (distance, height, in-range logit): linear, because a linear read-out is what the
    ridge probes measure and what the policy's first layer sees."""

    def __init__(self, latent_dim: int) -> None:
        super().__init__(latent_dim, 3)


def rise_loss(predicted: Tensor, targets: Tensor) -> Tensor:
    """Masked squared error on the standardised distance and height plus BCE on "rise in range", summed per image
    and averaged over the batch (as `vae_loss`); undefined (NaN) targets contribute exactly 0, gradient included."""
    mask = torch.isfinite(targets)
    clean = torch.where(mask, targets, torch.zeros_like(targets))
    squared = (predicted[:, :2] - clean[:, :2]).pow(2)
    bce = binary_cross_entropy_with_logits(predicted[:, 2], clean[:, 2], reduction="none")
    per_frame = torch.where(mask[:, :2], squared, 0.0).sum(1) + torch.where(mask[:, 2], bce, 0.0)
    return per_frame.sum() / max(1, len(targets))


__all__ = ["RiseHead", "RiseScale", "rise_loss", "rise_targets"]
