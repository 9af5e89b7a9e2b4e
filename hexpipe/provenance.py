"""Which code made an artifact. DVC reruns a stage when the code it lists changes; the resumable stages (collect,
train-vae, train-ppo) must then start afresh too, not continue episodes, epochs or checkpoints that older code made."""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent


@functools.cache
def code_fingerprint() -> str:
    """Short hash of every hexpipe source file (path and bytes); bytecode and data files do not count."""
    digest = hashlib.sha256()
    for path in sorted(PACKAGE.rglob("*.py")):
        digest.update(path.relative_to(PACKAGE).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]
