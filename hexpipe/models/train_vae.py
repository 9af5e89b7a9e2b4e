"""The train_vae stage: rollout frames -> in-memory dataset -> VAE training -> encoder export and reports.

The dataset is `vae_data` (frames streamed once into compact arrays, split by episode); this module is the seeded,
resumable training loop and the stage around it. Reports go to dvclive under `report_dir`: per-epoch loss curves,
final metrics and the figures of `vae_report` (a reconstruction grid, a 2-D PCA map of the latents), with the
`probes` of what the latent holds: a linear probe for "block within 1 m ahead", and ridge-regression probes from
the latent to what the gait needs: the distance to the next rise ahead and that rise's height. With
`vae.feature_weight` > 0 a training-only linear head (`rise_head`) makes the latent carry those two linearly.
"""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
import torch
from dvclive import Live
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from hexpipe.atomic import atomic_path
from hexpipe.config import VaeConfig
from hexpipe.models.probes import PROBE_DISTANCE_M, active_dims, knn_accuracy, linear_probe, ridge_r2, rise_probes
from hexpipe.models.rise_head import (
    RiseHead,
    RiseScale,
    profile_loss,
    rise_loss,
    rise_targets,
    standardise,
    terrain_profile,
)
from hexpipe.models.vae import (
    DEFAULT_CHANNELS,
    ConvVAE,
    channels_for,
    encoder_config,
    export_encoder,
    vae_loss,
)
from hexpipe.models.vae_data import VaeDataset, load_dataset, note_unlisted, split_by_episode
from hexpipe.models.vae_report import latent_map, recon_grid, rise_probe_figure
from hexpipe.provenance import code_fingerprint
from hexpipe.recording.reader import Frame
from hexpipe.speed import SPEED_JSON, machine, move_speed

CHECKPOINT = "checkpoint.pt"
CHECKPOINT_VERSION = 1
_EVAL_BATCH = 512
_EPOCH_KEYS = ("train/recon", "train/kl", "train/loss", "val/recon", "val/kl", "val/loss")
_RISE_KEYS = ("train/rise", "val/rise")  # the aux head's loss, logged only when it trains (feature_weight > 0)


def configure_threads(limit: int | None = None) -> int:
    """Use every core this process may run on (2 on the reference machine), but no more than `limit` or, without
    one, $OMP_NUM_THREADS: two trainings that each take every core slow each other down many times over, not two.
    Returns the thread count."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    if limit is None:
        limit = _env_threads()
    torch.set_num_threads(max(1, min(cores, limit) if limit else cores))
    return torch.get_num_threads()


def _env_threads() -> int | None:
    """$OMP_NUM_THREADS as a positive int, or None when unset or not one (OpenMP ignores such values too)."""
    try:
        value = int(os.environ.get("OMP_NUM_THREADS", ""))
    except ValueError:
        return None
    return value if value > 0 else None


def objective(
    model: ConvVAE,
    x: torch.Tensor,
    beta: float,
    noise: torch.Generator,
    head: RiseHead | None = None,
    targets: torch.Tensor | None = None,
    weight: float = 0.0,
    profile_weight: float = 0.0,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """Per-image (loss, recon, kl, rise) of batch x: loss = recon + beta * KL + weight * rise + profile_weight *
    profile, where rise is the aux head's `rise_loss` on the latent means against `targets` and profile its
    `profile_loss` on the band heights after them (the 4th term returned is rise + profile). Without a head or at
    zero weights, loss is exactly the plain VAE loss."""
    recon, mu, logvar = model(x, noise)
    loss = vae_loss(recon, x, mu, logvar, beta)
    if head is None or targets is None or (weight == 0 and profile_weight == 0):
        return loss.total, loss.recon, loss.kl, torch.zeros(())
    predicted = head(mu)
    rise = rise_loss(predicted, targets)
    total = loss.total + weight * rise
    if profile_weight > 0:
        profile = profile_loss(predicted[:, 3:], targets[:, 3:])
        total, rise = total + profile_weight * profile, rise + profile
    return total, loss.recon, loss.kl, rise


def train_step(
    model: ConvVAE,
    optimizer: torch.optim.Optimizer,
    x: torch.Tensor,
    beta: float,
    noise: torch.Generator,
    head: RiseHead | None = None,
    targets: torch.Tensor | None = None,
    weight: float = 0.0,
    profile_weight: float = 0.0,
) -> tuple[float, float, float, float]:
    """One optimiser step on batch x (and the head, if any); returns per-image (loss, recon, kl, rise)."""
    terms = objective(model, x, beta, noise, head, targets, weight, profile_weight)
    optimizer.zero_grad(set_to_none=True)
    terms[0].backward()
    optimizer.step()
    loss, recon, kl, rise = (t.item() for t in terms)
    return loss, recon, kl, rise


@torch.no_grad()
def evaluate(
    model: ConvVAE,
    data: VaeDataset,
    idx: np.ndarray,
    beta: float,
    seed: int,
    head: RiseHead | None = None,
    targets: torch.Tensor | None = None,
    weight: float = 0.0,
    profile_weight: float = 0.0,
) -> dict[str, float]:
    """Mean per-image recon / KL / loss (and the head's rise loss) on `idx`, with z sampled from a fixed-seed
    generator (comparable across epochs and to the training figures). `targets` covers all frames of `data`."""
    model.eval()
    noise = torch.Generator().manual_seed(seed)
    totals = np.zeros(4)
    for start in range(0, len(idx), _EVAL_BATCH):
        batch = idx[start : start + _EVAL_BATCH]
        x = data.batch(batch)
        terms = objective(model, x, beta, noise, head, None if targets is None else targets[batch], weight,
                          profile_weight)
        totals += len(x) * np.array([t.item() for t in terms])
    model.train()
    loss_m, recon_m, kl_m, rise_m = totals / max(1, len(idx))
    out = {"recon": float(recon_m), "kl": float(kl_m), "loss": float(loss_m)}
    return out | ({"rise": float(rise_m)} if head is not None else {})


@torch.no_grad()
def latent_means(model: ConvVAE, data: VaeDataset, idx: np.ndarray) -> np.ndarray:
    """(n, latent_dim) float32 posterior means of the frames `idx`."""
    model.eval()
    out = [model.encoder(data.batch(idx[s : s + _EVAL_BATCH]))[0] for s in range(0, len(idx), _EVAL_BATCH)]
    model.train()
    return torch.cat(out).numpy() if out else np.zeros((0, model.latent_dim), np.float32)


# --------------------------------------------------------------------------------------------- checkpoint


def _checkpoint_key(cfg: VaeConfig, data: VaeDataset) -> str:
    """What must match to resume: everything but epochs and output paths, the data and the code fingerprints."""
    settings = cfg.model_dump(exclude={"epochs", "out_dir", "report_dir"})
    return json.dumps(
        {
            "version": CHECKPOINT_VERSION,
            "code": code_fingerprint(),
            "cfg": settings,
            "channels": DEFAULT_CHANNELS,
            "data": data.fingerprint(),
        },
        sort_keys=True,
    )


def _save_checkpoint(path: Path, state: dict[str, Any]) -> None:
    with atomic_path(path) as tmp:
        torch.save(state, tmp)


def _load_checkpoint(path: Path, key: str, max_epochs: int, console: Console) -> dict[str, Any] | None:
    if not path.is_file():
        return None
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # unreadable checkpoints are only a lost head start
        console.log(f"[yellow]ignoring unreadable checkpoint {path} ({type(exc).__name__}); starting fresh")
        return None
    if state.get("key") != key:
        console.log(f"[yellow]{path} was trained with other settings or data; starting fresh")
        return None
    if state["epoch"] > max_epochs:
        console.log(f"[yellow]{path} is past epoch {max_epochs} ({state['epoch']}); starting fresh")
        return None
    return state


# ---------------------------------------------------------------------------------------------------- stage


def _progress(console: Console) -> Progress:
    return Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        TextColumn("{task.fields[status]}"),
        console=console,
    )


def _train_epoch(
    model: ConvVAE,
    optimizer: torch.optim.Optimizer,
    data: VaeDataset,
    train_idx: np.ndarray,
    cfg: VaeConfig,
    shuffle: torch.Generator,
    noise: torch.Generator,
    progress: Progress,
    epoch: int,
    head: RiseHead | None = None,
    targets: torch.Tensor | None = None,
) -> dict[str, float]:
    """One pass over the shuffled training frames; per-image means of the batch losses, and images/s
    (batch assembly + optimiser steps, excluding evaluation). `targets` covers all frames of `data`."""
    order = torch.from_numpy(train_idx)[torch.randperm(len(train_idx), generator=shuffle)]
    task = progress.add_task(f"epoch {epoch}/{cfg.epochs}", total=math.ceil(len(order) / cfg.batch_size), status="")
    sums, seen, busy = np.zeros(4), 0, 0.0
    for start in range(0, len(order), cfg.batch_size):
        tic = time.perf_counter()
        batch = order[start : start + cfg.batch_size]
        x = data.batch(batch)
        args = (model, optimizer, x, cfg.beta, noise)
        if head is not None and targets is not None:
            args += (head, targets[batch], cfg.feature_weight, cfg.profile_weight)
        sums += len(x) * np.array(train_step(*args))
        busy += time.perf_counter() - tic
        seen += len(x)
        progress.update(task, advance=1, status=f"loss {sums[0] / seen:.2f}")
    loss, recon, kl, rise = sums / seen
    return {
        "epoch": float(epoch),
        "train/loss": float(loss),
        "train/recon": float(recon),
        "train/kl": float(kl),
        **({"train/rise": float(rise)} if head is not None else {}),
        "images_per_s": seen / busy,
    }


def train_vae(cfg: VaeConfig, frames: Iterable[Frame] | None = None, threads: int | None = None,
              console: Console | None = None) -> dict[str, float]:
    """Run the stage; frames=None reads cfg.data_dir; threads caps torch's threads (see configure_threads).
    Returns the final metrics (as in metrics.json, flat)."""
    console = console or Console()
    threads = configure_threads(threads)
    if frames is None:
        note_unlisted(Path(cfg.data_dir), console)
    data = load_dataset(cfg, frames)
    train_idx, val_idx = split_by_episode(data, cfg.val_fraction, cfg.seed)
    n_val_eps = len(np.unique(data.episode_index[val_idx]))
    console.log(
        f"{data.modality}: {len(train_idx)} train / {len(val_idx)} val frames "
        f"({len(data.episodes) - n_val_eps} / {n_val_eps} episodes), raw {data.input_shape}, "
        f"{threads} threads"
    )

    out_dir, report_dir = Path(cfg.out_dir), Path(cfg.report_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    torch.manual_seed(cfg.seed)
    model = ConvVAE(channels_for(cfg.modality), cfg.image_size, cfg.latent_dim).to(memory_format=torch.channels_last)
    # The terrain profile per band (height maps only): the report's per-band probes, and the head's extra targets
    # at profile_weight > 0 (the config allows that for height maps only).
    profile = (terrain_profile(data.images, cfg.profile_bands, cfg.profile_corridor)
               if cfg.modality == "heightmap" else None)
    learn_profile = cfg.profile_weight > 0
    # The aux head exists only at a weight > 0, so that 0 is the plain VAE to the bit (same init, same steps); its
    # profile outputs only at profile_weight > 0, so that 0 is the rise head alone to the bit.
    head = (RiseHead(cfg.latent_dim, cfg.profile_bands if learn_profile else 0)
            if cfg.feature_weight > 0 or learn_profile else None)
    targets = None
    if head is not None:
        scale = RiseScale.fit(data.rise_distance[train_idx], data.rise_height[train_idx])
        targets = rise_targets(data.rise_distance, data.rise_height, scale)
        if learn_profile and profile is not None:
            targets = torch.cat([targets, standardise(profile, train_idx)], dim=1)
    epoch_keys = _EPOCH_KEYS + (_RISE_KEYS if head is not None else ())
    params = [*model.parameters(), *(head.parameters() if head is not None else ())]
    optimizer = torch.optim.Adam(params, lr=cfg.learning_rate)
    shuffle = torch.Generator().manual_seed(cfg.seed)
    noise = torch.Generator().manual_seed(cfg.seed + 1)
    history: list[dict[str, float]] = []

    key = _checkpoint_key(cfg, data)
    ckpt_path = out_dir / CHECKPOINT
    state = _load_checkpoint(ckpt_path, key, cfg.epochs, console)
    if state is not None:
        model.load_state_dict(state["model"])
        if head is not None:
            head.load_state_dict(state["head"])
        optimizer.load_state_dict(state["optimizer"])
        shuffle.set_state(state["shuffle_rng"])
        noise.set_state(state["noise_rng"])
        torch.set_rng_state(state["torch_rng"])
        history = list(state["history"])
        console.log(f"resuming from {ckpt_path} after epoch {state['epoch']}")

    live = Live(str(report_dir), dvcyaml=False, save_dvc_exp=False)
    for past in history:  # a fresh report that carries the resumed epochs' curves
        for name in epoch_keys:
            live.log_metric(name, past[name])
        live.next_step()

    with _progress(console) as progress:
        for epoch in range(len(history) + 1, cfg.epochs + 1):
            row = _train_epoch(model, optimizer, data, train_idx, cfg, shuffle, noise, progress, epoch, head, targets)
            val = evaluate(model, data, val_idx, cfg.beta, cfg.seed + 2, head, targets, cfg.feature_weight,
                           cfg.profile_weight)
            row |= {f"val/{k}": v for k, v in val.items()}
            history.append(row)
            for name in epoch_keys:
                live.log_metric(name, row[name])
            live.next_step()
            console.log(
                f"epoch {epoch}: train loss {row['train/loss']:.2f}, val loss {row['val/loss']:.2f} "
                f"(recon {row['val/recon']:.2f}, KL {row['val/kl']:.2f}"
                + (f", rise {row['val/rise']:.3f}" if head is not None else "")
                + f"), {row['images_per_s']:.0f} images/s"
            )
            _save_checkpoint(
                ckpt_path,
                {
                    "key": key,
                    "epoch": epoch,
                    "model": model.state_dict(),
                    **({"head": head.state_dict()} if head is not None else {}),
                    "optimizer": optimizer.state_dict(),
                    "shuffle_rng": shuffle.get_state(),
                    "noise_rng": noise.get_state(),
                    "torch_rng": torch.get_rng_state(),
                    "history": history,
                },
            )

    export_encoder(
        model,
        out_dir,
        encoder_config(model, cfg.modality, data.input_shape, beta=cfg.beta, epochs=len(history), seed=cfg.seed),
        head,
    )

    train_mu, val_mu = latent_means(model, data, train_idx), latent_means(model, data, val_idx)
    block_ahead = data.obstacle_distance < PROBE_DISTANCE_M
    # The probe of the issue and the paper's figure 4: "block ahead within 1 m" against "no block ahead"
    # (nothing raised within the 3 m range). Frames with a block 1-3 m ahead belong to neither class; the
    # stricter threshold probe below keeps them as negatives and is reported beside it.
    two_class = block_ahead | ~np.isfinite(data.obstacle_distance)
    tr, va = train_idx[two_class[train_idx]], val_idx[two_class[val_idx]]
    probe_accuracy, probe_baseline = linear_probe(
        latent_means(model, data, tr), block_ahead[tr], latent_means(model, data, va), block_ahead[va]
    )
    threshold_accuracy, threshold_baseline = linear_probe(
        train_mu, block_ahead[train_idx], val_mu, block_ahead[val_idx]
    )
    train_rise = (data.rise_distance[train_idx], data.rise_height[train_idx])
    val_rise = (data.rise_distance[val_idx], data.rise_height[val_idx])
    rise = rise_probes(train_mu, train_rise, val_mu, val_rise)
    # what the latent carries of each band of the map, rear (band 0) to front
    band_r2 = {} if profile is None else {
        f"probe/profile_r2/band{k}": ridge_r2(train_mu, profile[train_idx, k], val_mu, profile[val_idx, k])
        for k in range(cfg.profile_bands)}
    live.log_image("recon_grid.png", recon_grid(model, data, val_idx))
    live.log_image("latent_map.png", latent_map(val_mu, block_ahead[val_idx]))
    live.log_image("rise_probes.png", rise_probe_figure(train_mu, train_rise, val_mu, val_rise, rise))

    last = history[-1]
    metrics = {name: last[name] for name in epoch_keys}
    metrics |= {
        "train/images_per_s": float(np.median([h["images_per_s"] for h in history])),
        "probe_accuracy": probe_accuracy,
        "probe_baseline": probe_baseline,
        "probe_threshold_accuracy": threshold_accuracy,
        "probe_threshold_baseline": threshold_baseline,
        "probe_knn_accuracy": knn_accuracy(train_mu, block_ahead[train_idx], val_mu, block_ahead[val_idx]),
        "latent/active_dims": active_dims(val_mu),
        **{f"probe/{name}": value for name, value in rise.items()},
        **band_r2,
        "data/train_frames": len(train_idx),
        "data/val_frames": len(val_idx),
        "data/val_episodes": n_val_eps,
        "epochs": len(history),
    }
    for name, value in metrics.items():
        if name not in epoch_keys:
            live.log_metric(name, value, plot=False)
    live.end()
    move_speed(report_dir / "metrics.json", report_dir / SPEED_JSON, ("train/images_per_s",), machine())  # results only
    console.log(
        f"val loss {metrics['val/loss']:.2f} (recon {metrics['val/recon']:.2f}, KL {metrics['val/kl']:.2f}); "
        f"probe {probe_accuracy:.3f} vs baseline {probe_baseline:.3f} (threshold probe {threshold_accuracy:.3f}); "
        f"rise probes R² distance {rise['rise_distance_r2']:.3f}, height {rise['rise_height_r2']:.3f} "
        f"(kNN {rise['rise_distance_knn_r2']:.3f}, {rise['rise_height_knn_r2']:.3f}); "
        + (f"profile R² rear to front {' '.join(f'{v:.2f}' for v in band_r2.values())}; " if band_r2 else "")
        + f"{metrics['latent/active_dims']}/{cfg.latent_dim} active latent dims; "
        f"{metrics['train/images_per_s']:.0f} images/s; encoder -> {out_dir}"
    )
    return metrics


__all__ = ["configure_threads", "evaluate", "latent_means", "objective", "train_step", "train_vae"]
