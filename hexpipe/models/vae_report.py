"""The VAE report's figures: reconstructions of validation frames, a PCA map of the latents, the rise probes."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch
from matplotlib.figure import Figure

from hexpipe.models.probes import ridge_predict
from hexpipe.models.vae import ConvVAE
from hexpipe.models.vae_data import VaeDataset


def _show(ax: Any, chw: np.ndarray) -> None:
    if chw.shape[0] == 3:
        ax.imshow(chw.transpose(1, 2, 0), vmin=0.0, vmax=1.0)
    else:
        ax.imshow(chw[0], cmap="viridis", vmin=0.0, vmax=1.0)
    ax.set_xticks([])
    ax.set_yticks([])


@torch.no_grad()
def recon_grid(model: ConvVAE, data: VaeDataset, val_idx: np.ndarray, n: int = 8) -> Figure:
    """Top row: 8 evenly spaced validation inputs; bottom row: decoder(posterior mean) of each."""
    picks = val_idx[np.linspace(0, len(val_idx) - 1, min(n, len(val_idx))).round().astype(int)]
    model.eval()
    x = data.batch(picks)
    recon = model.decoder(model.encoder(x)[0]).numpy()
    model.train()
    fig = Figure(figsize=(1.6 * len(picks), 3.6), layout="constrained")
    axes = fig.subplots(2, len(picks), squeeze=False)
    for col in range(len(picks)):
        _show(axes[0, col], x[col].numpy())
        _show(axes[1, col], recon[col])
        distance = data.obstacle_distance[picks[col]]
        axes[0, col].set_title("no block" if math.isinf(distance) else f"block {distance:.2f} m", fontsize=8)
    axes[0, 0].set_ylabel("input")
    axes[1, 0].set_ylabel("reconstruction")
    fig.suptitle(f"VAE {data.modality}: validation inputs and reconstructions (from posterior mean)")
    return fig


def latent_map(mu: np.ndarray, block_ahead: np.ndarray) -> Figure:
    """2-D PCA of validation latent means coloured by 'block within 1 m ahead' (cf. the paper's figure 4)."""
    centred = mu - mu.mean(0)
    _, s, vt = np.linalg.svd(centred, full_matrices=False)
    coords = centred @ vt[:2].T
    if coords.shape[1] < 2:  # latent_dim == 1
        coords = np.column_stack([coords, np.zeros(len(coords))])
    explained = (s**2 / max(float((s**2).sum()), 1e-12))[:2]
    fig = Figure(figsize=(5.5, 4.5), layout="constrained")
    ax = fig.subplots()
    for flag, colour, label in (
        (False, "tab:blue", "no block within 1 m"),
        (True, "tab:red", "block within 1 m"),
    ):
        sel = block_ahead == flag
        ax.scatter(coords[sel, 0], coords[sel, 1], s=6, alpha=0.6, c=colour, label=f"{label} ({sel.sum()})")
    ax.set_xlabel(f"PC1 ({100 * explained[0]:.0f}% var)")
    ax.set_ylabel(f"PC2 ({100 * explained[1]:.0f}% var)" if len(explained) > 1 else "PC2")
    ax.set_title("Validation latent means (PCA)")
    ax.legend(loc="best", fontsize=8)
    return fig


def rise_probe_figure(
    train_mu: np.ndarray, train_rise: tuple[np.ndarray, np.ndarray], val_mu: np.ndarray,
    val_rise: tuple[np.ndarray, np.ndarray], metrics: dict[str, float],
) -> Figure:
    """Ridge predictions against the truth on validation frames with a rise in range: distance and height."""
    fig = Figure(figsize=(9, 4), layout="constrained")
    axes = fig.subplots(1, 2)
    in_train, in_val = np.isfinite(train_rise[0]), np.isfinite(val_rise[0])
    for ax, k, name, unit in ((axes[0], 0, "rise_distance", "distance to the next rise"),
                              (axes[1], 1, "rise_height", "height of the next rise")):
        tr, va = in_train & np.isfinite(train_rise[k]), in_val & np.isfinite(val_rise[k])
        ax.set(xlabel=f"true {unit} (m)", ylabel="ridge prediction (m)")
        if tr.sum() < 2 or va.sum() < 1:
            ax.set_title(f"{name}: too few frames")
            continue
        truth = val_rise[k][va]
        ax.scatter(truth, ridge_predict(train_mu[tr], train_rise[k][tr], val_mu[va]), s=5, alpha=0.5)
        lo, hi = float(truth.min()), float(truth.max())
        ax.plot([lo, hi], [lo, hi], color="k", lw=0.8)
        ax.set_title(f"{name}: R² {metrics[f'{name}_r2']:.2f} (kNN {metrics[f'{name}_knn_r2']:.2f}), {va.sum()} frames",
                     fontsize=9)
    fig.suptitle("Probes from the latent mean, held-out episodes, frames with a rise within the height map's reach")
    return fig
