"""Weights-only model files: tensors in, never code.

Evaluation and `hexpipe play` load networks only from state dicts read with `torch.load(weights_only=True)`: its
unpickler accepts tensors and plain containers and refuses any other callable, so a crafted file cannot run code
(a plain `pickle.load`, as in SB3's zip and VecNormalize's .pkl, would run it). Every failure (missing, empty,
truncated, random bytes, a refused object, not a mapping of tensors) is one `WeightsError` line naming the file.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import torch

from hexpipe.atomic import atomic_path


class WeightsError(ValueError):
    """A weights file that is missing, corrupt or holds anything but named tensors; one line naming the file."""


def load_state_dict(path: str | Path) -> dict[str, torch.Tensor]:
    """{name: tensor} from a `torch.save(state_dict)` file, on the CPU, without running any code from it."""
    path = Path(path)
    if not path.is_file():
        raise WeightsError(f"{path}: weights file not found")
    if path.stat().st_size == 0:
        raise WeightsError(f"{path}: empty weights file (0 bytes)")
    try:
        with warnings.catch_warnings():  # e.g. "Detected pickle protocol 4": the one-line error says enough
            warnings.simplefilter("ignore")
            state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # EOFError, UnpicklingError, RuntimeError (bad zip), OSError alike
        raise WeightsError(f"{path}: not a readable weights-only file ({_reason(exc)})") from None
    if not isinstance(state, dict) or not all(
        isinstance(k, str) and isinstance(v, torch.Tensor) for k, v in state.items()
    ):
        raise WeightsError(f"{path}: expected a mapping of names to tensors, found {type(state).__name__}")
    return state


def save_state_dict(state: dict[str, torch.Tensor], path: str | Path) -> None:
    """Write `state` (detached CPU copies) to `path` atomically."""
    tensors = {k: v.detach().cpu().clone() for k, v in state.items()}
    with atomic_path(Path(path)) as tmp:
        torch.save(tensors, tmp)


def _reason(exc: BaseException) -> str:
    """A short cause, without torch's advice to retry with weights_only=False."""
    text = str(exc)
    blocked = re.search(r"unsupported GLOBAL (\S+)", text) or re.search(r"Unsupported global: GLOBAL (\S+)", text)
    if blocked:
        return f"it names {blocked.group(1).rstrip('.')}, which a weights file never does; refused, nothing was run"
    if "Weights only load failed" in text:
        return "not tensor data; refused, nothing was run"
    first = text.strip().splitlines()[0] if text.strip() else ""
    return f"{type(exc).__name__}: {first}" if first else f"{type(exc).__name__}, truncated or not a torch file"
