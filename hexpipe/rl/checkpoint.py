"""Saving and loading a policy with its observation normalisation, atomically.

A checkpoint is a folder `step-<timesteps>/` holding `model.zip` and `vecnormalize.pkl`; it is written under a
temporary name and renamed when complete (`atomic.atomic_dir`), so an interrupted save never leaves a half
checkpoint behind.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from stable_baselines3.common.base_class import BaseAlgorithm

from hexpipe.atomic import atomic_dir

MODEL = "model.zip"
NORMALISATION = "vecnormalize.pkl"


def save_policy(model: BaseAlgorithm, directory: Path) -> None:
    """Write model.zip and vecnormalize.pkl into `directory` (replaced as a whole)."""
    with atomic_dir(directory) as tmp:
        model.save(tmp / MODEL)
        normaliser = model.get_vec_normalize_env()
        if normaliser is not None:
            normaliser.save(str(tmp / NORMALISATION))


def save_checkpoint(model: BaseAlgorithm, root: Path, keep: int = 2) -> Path:
    """Save `root/step-<timesteps>` and drop all but the newest `keep` checkpoints."""
    path = Path(root) / f"step-{model.num_timesteps:09d}"
    save_policy(model, path)
    for stale in sorted(Path(root).glob("step-*[0-9]"))[:-keep]:
        shutil.rmtree(stale, ignore_errors=True)
    return path


def checkpoint_step(path: Path) -> int:
    """The timesteps a checkpoint folder `step-<timesteps>` was saved at."""
    return int(Path(path).name.removeprefix("step-"))


def complete_checkpoints(root: Path, at_most: int | None = None) -> list[Path]:
    """Checkpoints holding a model, newest first; with `at_most`, only those saved at or below that many steps
    (a shorter budget must never reuse a longer run)."""
    found = [p for p in Path(root).glob("step-*[0-9]") if p.name[5:].isdigit() and (p / MODEL).is_file()]
    found = [p for p in found if at_most is None or checkpoint_step(p) <= at_most]
    return sorted(found, key=checkpoint_step, reverse=True)
