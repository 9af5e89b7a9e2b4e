"""The train_vae stage: rollout frames -> in-memory dataset -> VAE training -> encoder export and reports.

Frames are streamed once into compact arrays (the `preprocess` output, stored as uint8 for rgb and float16 for
height maps), split into train/validation by episode so no rollout leaks across the split, and trained with a
seeded, resumable loop. Reports go to dvclive under `report_dir`: per-epoch loss curves, final metrics, a
reconstruction grid, a 2-D PCA map of the latents and a linear probe for "block within 1 m ahead".
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from dvclive import Live
from matplotlib.figure import Figure
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from hexpipe.config import VaeConfig
from hexpipe.models.vae import (
    DEFAULT_CHANNELS,
    ConvVAE,
    channels_for,
    encoder_config,
    export_encoder,
    preprocess,
    vae_loss,
)
from hexpipe.provenance import code_fingerprint
from hexpipe.recording.reader import Frame, RecordingError, iter_frames
from hexpipe.speed import SPEED_JSON, move_speed

CHECKPOINT = "checkpoint.pt"
CHECKPOINT_VERSION = 1
PROBE_DISTANCE_M = 1.0  # "block ahead" label: obstacle_distance below this (the paper's figure 4)
_CHUNK = 256  # frames preprocessed per call while streaming
_EVAL_BATCH = 512
_EPOCH_KEYS = ("train/recon", "train/kl", "train/loss", "val/recon", "val/kl", "val/loss")


class VaeDataError(ValueError):
    """Rollouts unusable for VAE training (none, wrong modality, too few episodes); one line."""


def configure_threads() -> int:
    """Use every core this process may run on (2 on the reference machine); returns the thread count."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    torch.set_num_threads(max(1, cores))
    return torch.get_num_threads()


# ----------------------------------------------------------------------------------------------------- data


@dataclass
class VaeDataset:
    """All frames of one modality, preprocessed, plus per-frame episode and obstacle labels."""

    modality: str
    images: np.ndarray  # (N, C, S, S): uint8 (x255) for rgb, float16 for heightmap; values in [0, 1]
    episode_index: np.ndarray  # (N,) int32 index into `episodes`
    episodes: list[str]  # episode names (MCAP stems), sorted
    obstacle_distance: np.ndarray  # (N,) float32 m to the next raised terrain ahead; inf if none
    input_shape: tuple[int, ...]  # one raw frame as logged: (H, W, 3) or (R, C)

    def __len__(self) -> int:
        return len(self.images)

    def batch(self, idx: np.ndarray | torch.Tensor) -> torch.Tensor:
        """float32 (n, C, S, S) in [0, 1] for the given frame indices."""
        x = torch.from_numpy(self.images[np.asarray(idx)])
        x = x.float().div_(255.0) if x.dtype == torch.uint8 else x.float()
        return x.contiguous(memory_format=torch.channels_last)

    def fingerprint(self) -> str:
        """Hash of the frames and their episode labels; a checkpoint is only resumed on the same data."""
        h = hashlib.blake2b(digest_size=16)
        h.update(json.dumps([self.modality, self.episodes, list(self.input_shape)]).encode())
        for array in (self.images, self.episode_index, self.obstacle_distance):
            h.update(np.ascontiguousarray(array).data)
        return h.hexdigest()


def _quantise(x: np.ndarray, modality: str) -> np.ndarray:
    """Compact storage of preprocess() output: lossless for rgb at native size, <= 2.5e-4 for heights."""
    if modality == "rgb":
        return np.rint(x * 255.0).astype(np.uint8)
    return x.astype(np.float16)


def build_dataset(frames: Iterable[Frame], modality: str, image_size: int, source: str = "frames") -> VaeDataset:
    """Stream frames once into a VaeDataset. `source` names the data in error messages (e.g. the folder)."""
    chunks: list[np.ndarray] = []
    pending: list[np.ndarray] = []
    episode_names: list[str] = []
    distances: list[float] = []
    present: set[str] = set()
    input_shape: tuple[int, ...] | None = None
    n_frames = 0

    def flush() -> None:
        if pending:
            chunks.append(_quantise(preprocess(np.stack(pending), modality, image_size), modality))
            pending.clear()

    for frame in frames:
        n_frames += 1
        present.update(name for name in ("rgb", "heightmap") if getattr(frame, name) is not None)
        raw = getattr(frame, modality)
        if raw is None:
            continue
        raw = np.asarray(raw)
        if input_shape is None:
            input_shape = raw.shape
        elif raw.shape != input_shape:
            raise VaeDataError(
                f"{source}: {modality} frames change shape ({input_shape} then {raw.shape} in episode "
                f"{frame.episode!r}); record all episodes with the same sensor config"
            )
        pending.append(raw)
        episode_names.append(frame.episode)
        distance = frame.meta.get("obstacle_distance")
        distances.append(math.inf if distance is None else float(distance))
        if len(pending) >= _CHUNK:
            flush()
    flush()

    if n_frames == 0:
        raise VaeDataError(f"{source}: no frames found (run the collect stage first)")
    if input_shape is None:
        contains = ", ".join(sorted(present)) or "no sensor data"
        raise VaeDataError(f"{source}: no {modality!r} frames (rollouts contain: {contains})")
    episodes = sorted(set(episode_names))
    if len(episodes) < 2:
        raise VaeDataError(
            f"{source}: only one episode ({episodes[0]!r}); need at least 2 to split train/validation by episode"
        )
    lookup = {name: i for i, name in enumerate(episodes)}
    return VaeDataset(
        modality=modality,
        images=np.concatenate(chunks),
        episode_index=np.array([lookup[name] for name in episode_names], dtype=np.int32),
        episodes=episodes,
        obstacle_distance=np.array(distances, dtype=np.float32),
        input_shape=tuple(int(s) for s in input_shape),
    )


def split_by_episode(data: VaeDataset, val_fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(train, val) frame indices; a seeded val_fraction of episodes (>= 1, <= all but 1) is val."""
    n_episodes = len(data.episodes)
    n_val = min(max(1, round(val_fraction * n_episodes)), n_episodes - 1)
    val_episodes = np.random.default_rng(seed).permutation(n_episodes)[:n_val]
    is_val = np.isin(data.episode_index, val_episodes)
    return np.flatnonzero(~is_val), np.flatnonzero(is_val)


def _present_modalities(folder: Path) -> set[str]:
    """Which sensors the rollouts in `folder` hold (looks at the first frames only; for error messages)."""
    present: set[str] = set()
    try:
        for i, frame in enumerate(iter_frames(folder)):
            present.update(name for name in ("rgb", "heightmap") if getattr(frame, name) is not None)
            if i >= 50 or len(present) == 2:
                break
    except RecordingError:
        pass
    return present


def load_dataset(cfg: VaeConfig, frames: Iterable[Frame] | None = None) -> VaeDataset:
    """The dataset from `frames`, or from the rollouts in cfg.data_dir when frames is None."""
    if frames is not None:
        return build_dataset(frames, cfg.modality, cfg.image_size)
    folder = Path(cfg.data_dir)
    if not folder.exists():
        raise VaeDataError(f"{cfg.data_dir}: no such folder (run the collect stage first)")
    try:
        return build_dataset(iter_frames(folder, (cfg.modality,)), cfg.modality, cfg.image_size, cfg.data_dir)
    except VaeDataError as exc:
        # Reading one modality may leave the others unloaded; look again to say what the rollouts do hold.
        if f"no {cfg.modality!r} frames" not in str(exc):
            raise
        contains = ", ".join(sorted(_present_modalities(folder))) or "no sensor data"
        raise VaeDataError(f"{cfg.data_dir}: no {cfg.modality!r} frames (rollouts contain: {contains})") from None


# ------------------------------------------------------------------------------------------------ training


def train_step(
    model: ConvVAE, optimizer: torch.optim.Optimizer, x: torch.Tensor, beta: float, noise: torch.Generator
) -> tuple[float, float, float]:
    """One optimiser step on batch x; returns per-image (loss, recon, kl) of this batch."""
    recon, mu, logvar = model(x, noise)
    loss = vae_loss(recon, x, mu, logvar, beta)
    optimizer.zero_grad(set_to_none=True)
    loss.total.backward()
    optimizer.step()
    return loss.total.item(), loss.recon.item(), loss.kl.item()


@torch.no_grad()
def evaluate(model: ConvVAE, data: VaeDataset, idx: np.ndarray, beta: float, seed: int) -> dict[str, float]:
    """Mean per-image recon / KL / loss on `idx`, with z sampled from a fixed-seed generator (comparable
    across epochs and to the training figures)."""
    model.eval()
    noise = torch.Generator().manual_seed(seed)
    totals = np.zeros(3)
    for start in range(0, len(idx), _EVAL_BATCH):
        x = data.batch(idx[start : start + _EVAL_BATCH])
        recon, mu, logvar = model(x, noise)
        loss = vae_loss(recon, x, mu, logvar, beta)
        totals += len(x) * np.array([loss.recon.item(), loss.kl.item(), loss.total.item()])
    model.train()
    recon_m, kl_m, loss_m = totals / max(1, len(idx))
    return {"recon": float(recon_m), "kl": float(kl_m), "loss": float(loss_m)}


@torch.no_grad()
def latent_means(model: ConvVAE, data: VaeDataset, idx: np.ndarray) -> np.ndarray:
    """(n, latent_dim) float32 posterior means of the frames `idx`."""
    model.eval()
    out = [model.encoder(data.batch(idx[s : s + _EVAL_BATCH]))[0] for s in range(0, len(idx), _EVAL_BATCH)]
    model.train()
    return torch.cat(out).numpy() if out else np.zeros((0, model.latent_dim), np.float32)


def linear_probe(
    x_train: np.ndarray, y_train: np.ndarray, x_val: np.ndarray, y_val: np.ndarray, l2: float = 1e-3
) -> tuple[float, float]:
    """Logistic regression on standardised latents (L-BFGS, L2 on weights) -> (val accuracy, baseline).

    The baseline is the best constant predictor on val, max(p, 1 - p), so the probe must beat class imbalance.
    Both are NaN when there is nothing to fit or score.
    """
    if len(y_val) == 0 or len(y_train) == 0:
        return math.nan, math.nan
    mean, std = x_train.mean(0), x_train.std(0) + 1e-6
    xt = torch.from_numpy(((x_train - mean) / std).astype(np.float32))
    xv = torch.from_numpy(((x_val - mean) / std).astype(np.float32))
    yt = torch.from_numpy(y_train.astype(np.float32))
    w = torch.zeros(xt.shape[1], requires_grad=True)
    b = torch.zeros((), requires_grad=True)
    opt = torch.optim.LBFGS([w, b], lr=1.0, max_iter=200, line_search_fn="strong_wolfe")

    def closure() -> torch.Tensor:
        opt.zero_grad()
        loss = torch.nn.functional.binary_cross_entropy_with_logits(xt @ w + b, yt) + l2 * w.pow(2).sum()
        loss.backward()
        return loss

    opt.step(closure)
    with torch.no_grad():
        predicted = (xv @ w + b > 0).numpy()
    positive_rate = float(y_val.mean())
    return float((predicted == y_val.astype(bool)).mean()), max(positive_rate, 1.0 - positive_rate)


def knn_accuracy(x_train: np.ndarray, y_train: np.ndarray, x_val: np.ndarray, y_val: np.ndarray, k: int = 5) -> float:
    """Accuracy of a k-nearest-neighbour vote on standardised latents: is the information there at all,
    linearly readable or not (shown beside the linear probe)."""
    if len(x_val) == 0 or len(x_train) < k:
        return float("nan")
    mean, std = x_train.mean(0), x_train.std(0) + 1e-6
    xt, xv = torch.from_numpy((x_train - mean) / std), torch.from_numpy((x_val - mean) / std)
    nearest = torch.cdist(xv, xt).topk(k, largest=False).indices.numpy()
    vote = y_train[nearest].mean(axis=1) > 0.5
    return float((vote == y_val.astype(bool)).mean())


def active_dims(mu: np.ndarray, threshold: float = 0.01) -> int:
    """Latent dims whose posterior mean varies across frames (Var > threshold, Burda et al. 2016).

    A collapsed dim carries ~no information to PPO even if the standardised linear probe can still read it,
    so this sits beside probe_accuracy in the metrics.
    """
    return int((mu.var(0) > threshold).sum()) if len(mu) > 1 else 0


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
    tmp = path.with_name(f".{path.name}.tmp")
    torch.save(state, tmp)
    os.replace(tmp, path)


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


# ------------------------------------------------------------------------------------------------- reports


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
) -> dict[str, float]:
    """One pass over the shuffled training frames; per-image means of the batch losses, and images/s
    (batch assembly + optimiser steps, excluding evaluation)."""
    order = torch.from_numpy(train_idx)[torch.randperm(len(train_idx), generator=shuffle)]
    task = progress.add_task(f"epoch {epoch}/{cfg.epochs}", total=math.ceil(len(order) / cfg.batch_size), status="")
    sums, seen, busy = np.zeros(3), 0, 0.0
    for start in range(0, len(order), cfg.batch_size):
        tic = time.perf_counter()
        x = data.batch(order[start : start + cfg.batch_size])
        sums += len(x) * np.array(train_step(model, optimizer, x, cfg.beta, noise))
        busy += time.perf_counter() - tic
        seen += len(x)
        progress.update(task, advance=1, status=f"loss {sums[0] / seen:.2f}")
    loss, recon, kl = sums / seen
    return {
        "epoch": float(epoch),
        "train/loss": float(loss),
        "train/recon": float(recon),
        "train/kl": float(kl),
        "images_per_s": seen / busy,
    }


def train_vae(cfg: VaeConfig, frames: Iterable[Frame] | None = None) -> dict[str, float]:
    """Run the stage; frames=None reads cfg.data_dir. Returns the final metrics (as in metrics.json, flat)."""
    console = Console()
    threads = configure_threads()
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
    optimizer = torch.optim.Adam(model.parameters(), lr=cfg.learning_rate)
    shuffle = torch.Generator().manual_seed(cfg.seed)
    noise = torch.Generator().manual_seed(cfg.seed + 1)
    history: list[dict[str, float]] = []

    key = _checkpoint_key(cfg, data)
    ckpt_path = out_dir / CHECKPOINT
    state = _load_checkpoint(ckpt_path, key, cfg.epochs, console)
    if state is not None:
        model.load_state_dict(state["model"])
        optimizer.load_state_dict(state["optimizer"])
        shuffle.set_state(state["shuffle_rng"])
        noise.set_state(state["noise_rng"])
        torch.set_rng_state(state["torch_rng"])
        history = list(state["history"])
        console.log(f"resuming from {ckpt_path} after epoch {state['epoch']}")

    live = Live(str(report_dir), dvcyaml=False, save_dvc_exp=False)
    for past in history:  # a fresh report that carries the resumed epochs' curves
        for name in _EPOCH_KEYS:
            live.log_metric(name, past[name])
        live.next_step()

    with _progress(console) as progress:
        for epoch in range(len(history) + 1, cfg.epochs + 1):
            row = _train_epoch(model, optimizer, data, train_idx, cfg, shuffle, noise, progress, epoch)
            row |= {f"val/{k}": v for k, v in evaluate(model, data, val_idx, cfg.beta, cfg.seed + 2).items()}
            history.append(row)
            for name in _EPOCH_KEYS:
                live.log_metric(name, row[name])
            live.next_step()
            console.log(
                f"epoch {epoch}: train loss {row['train/loss']:.2f}, val loss {row['val/loss']:.2f} "
                f"(recon {row['val/recon']:.2f}, KL {row['val/kl']:.2f}), {row['images_per_s']:.0f} images/s"
            )
            _save_checkpoint(
                ckpt_path,
                {
                    "key": key,
                    "epoch": epoch,
                    "model": model.state_dict(),
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
    live.log_image("recon_grid.png", recon_grid(model, data, val_idx))
    live.log_image("latent_map.png", latent_map(val_mu, block_ahead[val_idx]))

    last = history[-1]
    metrics = {name: last[name] for name in _EPOCH_KEYS}
    metrics |= {
        "train/images_per_s": float(np.median([h["images_per_s"] for h in history])),
        "probe_accuracy": probe_accuracy,
        "probe_baseline": probe_baseline,
        "probe_threshold_accuracy": threshold_accuracy,
        "probe_threshold_baseline": threshold_baseline,
        "probe_knn_accuracy": knn_accuracy(train_mu, block_ahead[train_idx], val_mu, block_ahead[val_idx]),
        "latent/active_dims": active_dims(val_mu),
        "data/train_frames": len(train_idx),
        "data/val_frames": len(val_idx),
        "data/val_episodes": n_val_eps,
        "epochs": len(history),
    }
    for name, value in metrics.items():
        if name not in _EPOCH_KEYS:
            live.log_metric(name, value, plot=False)
    live.end()
    move_speed(report_dir / "metrics.json", report_dir / SPEED_JSON, ("train/images_per_s",))  # results only
    console.log(
        f"val loss {metrics['val/loss']:.2f} (recon {metrics['val/recon']:.2f}, KL {metrics['val/kl']:.2f}); "
        f"probe {probe_accuracy:.3f} vs baseline {probe_baseline:.3f} (threshold probe {threshold_accuracy:.3f}); "
        f"{metrics['latent/active_dims']}/{cfg.latent_dim} active latent dims; "
        f"{metrics['train/images_per_s']:.0f} images/s; encoder -> {out_dir}"
    )
    return metrics


__all__ = [
    "VaeDataError",
    "VaeDataset",
    "active_dims",
    "build_dataset",
    "configure_threads",
    "linear_probe",
    "load_dataset",
    "split_by_episode",
    "train_step",
    "train_vae",
]
