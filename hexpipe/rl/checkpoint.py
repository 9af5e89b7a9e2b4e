"""Saving and loading a policy with its observation normalisation, atomically.

A checkpoint is a folder `step-<timesteps>/` holding `model.zip` and `vecnormalize.pkl`; it is written under a
temporary name and renamed when complete, so an interrupted save never leaves a half checkpoint behind.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from stable_baselines3.common.base_class import BaseAlgorithm

MODEL = "model.zip"
NORMALISATION = "vecnormalize.pkl"


def save_policy(model: BaseAlgorithm, directory: Path) -> None:
    """Write model.zip and vecnormalize.pkl into `directory` (replaced as a whole)."""
    directory = Path(directory)
    directory.parent.mkdir(parents=True, exist_ok=True)
    tmp = directory.with_name(directory.name + ".tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir()
    model.save(tmp / MODEL)
    normaliser = model.get_vec_normalize_env()
    if normaliser is not None:
        normaliser.save(str(tmp / NORMALISATION))
    old = directory.with_name(directory.name + ".old")
    if directory.exists():
        directory.rename(old)
    tmp.rename(directory)
    shutil.rmtree(old, ignore_errors=True)


def save_checkpoint(model: BaseAlgorithm, root: Path, keep: int = 2) -> Path:
    """Save `root/step-<timesteps>` and drop all but the newest `keep` checkpoints."""
    path = Path(root) / f"step-{model.num_timesteps:09d}"
    save_policy(model, path)
    for stale in sorted(Path(root).glob("step-*[0-9]"))[:-keep]:
        shutil.rmtree(stale, ignore_errors=True)
    return path


def latest_checkpoint(root: Path) -> Path | None:
    complete = [p for p in sorted(Path(root).glob("step-*[0-9]")) if (p / MODEL).is_file()]
    return complete[-1] if complete else None
