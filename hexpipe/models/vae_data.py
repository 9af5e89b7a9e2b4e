"""The VAE's dataset: rollout frames streamed once into compact arrays, with episode and obstacle labels.

Frames are stored as the `preprocess` output (uint8 for rgb, float16 for height maps) and split into train and
validation by episode, so no rollout leaks across the split.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from rich.console import Console

from hexpipe import sensors as registry
from hexpipe.config import VaeConfig
from hexpipe.models.vae import preprocess
from hexpipe.recording.manifest import MANIFEST, listed_files
from hexpipe.recording.reader import Frame, RecordingError, iter_frames

_CHUNK = 256  # frames preprocessed per call while streaming


class VaeDataError(ValueError):
    """Rollouts unusable for VAE training (none, wrong modality, too few episodes); one line."""


@dataclass
class VaeDataset:
    """All frames of one modality, preprocessed, plus per-frame episode and obstacle labels."""

    modality: str
    images: np.ndarray  # (N, C, S, S): uint8 (x255) for rgb, float16 for heightmap; values in [0, 1]
    episode_index: np.ndarray  # (N,) int32 index into `episodes`
    episodes: list[str]  # episode names (MCAP stems), sorted
    obstacle_distance: np.ndarray  # (N,) float32 m to the next raised terrain ahead; inf if none
    input_shape: tuple[int, ...]  # one raw frame as logged: (H, W, 3) or (R, C)
    # the next rise within the height map's reach (Terrain.rise_ahead): m ahead (inf: none in range) and m high
    # (nan: none); both nan on frames logged before these labels existed
    rise_distance: np.ndarray | None = None  # (N,) float32
    rise_height: np.ndarray | None = None  # (N,) float32

    def __post_init__(self) -> None:
        unlabelled = np.full(len(self.images), np.nan, dtype=np.float32)
        if self.rise_distance is None:
            self.rise_distance = unlabelled
        if self.rise_height is None:
            self.rise_height = unlabelled.copy()

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
    if registry.get(modality).image.store_uint8:
        return np.rint(x * 255.0).astype(np.uint8)
    return x.astype(np.float16)


def build_dataset(frames: Iterable[Frame], modality: str, image_size: int, source: str = "frames") -> VaeDataset:
    """Stream frames once into a VaeDataset. `source` names the data in error messages (e.g. the folder)."""
    chunks: list[np.ndarray] = []
    pending: list[np.ndarray] = []
    episode_names: list[str] = []
    distances: list[float] = []
    rises: list[tuple[float, float]] = []
    present: set[str] = set()
    input_shape: tuple[int, ...] | None = None
    n_frames = 0

    def flush() -> None:
        if pending:
            chunks.append(_quantise(preprocess(np.stack(pending), modality, image_size), modality))
            pending.clear()

    for frame in frames:
        n_frames += 1
        present.update(frame.sensors)
        raw = frame.sensors.get(modality)
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
        rises.append(_rise_labels(frame.meta))
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
        rise_distance=np.array([d for d, _ in rises], dtype=np.float32),
        rise_height=np.array([h for _, h in rises], dtype=np.float32),
    )


def _rise_labels(meta: dict[str, Any]) -> tuple[float, float]:
    """(distance, height) of the next rise from a /step message: null is 'no rise in range' (inf, nan); a missing
    key is an older recording without the labels (nan, nan)."""
    if "rise_distance" not in meta:
        return math.nan, math.nan
    distance, height = meta["rise_distance"], meta.get("rise_height")
    if distance is None:
        return math.inf, math.nan
    return float(distance), math.nan if height is None else float(height)


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
            present.update(frame.sensors)
            if i >= 50 or len(present) == len(registry.SENSORS):
                break
    except RecordingError:
        pass
    return present


def note_unlisted(folder: Path, console: Console) -> None:
    """Say which files of a rollout folder are left out: those its manifest does not list (see iter_frames)."""
    listed = listed_files(folder) if folder.is_dir() else None
    if listed is None and folder.is_dir():
        console.log(f"[yellow]{folder} has no {MANIFEST}: training on every .mcap file in it")
    elif listed is not None and listed[1]:
        names = ", ".join(p.name for p in listed[1][:3]) + (", ..." if len(listed[1]) > 3 else "")
        console.log(f"[yellow]ignoring {len(listed[1])} .mcap file(s) in {folder} not in its {MANIFEST}: {names}")


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
