"""Atomic file writes: every artifact appears whole or not at all.

Each output is written under a hidden temporary name beside its target (`.NAME.tmp<suffix>`, same folder, so the
final `os.replace` is atomic on POSIX) and renamed when complete. An interrupted write leaves the old file, or no
file, plus at most a stray hidden temp file that the next write overwrites.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any


def temp_path(path: Path) -> Path:
    """The hidden temp name for `path`; keeps the suffix so tools that pick a format by extension still work."""
    return path.with_name(f".{path.stem}.tmp{path.suffix}")


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temp path to write `path` through; rename it into place on success, delete it on any error."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = temp_path(path)
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_bytes(path: str | Path, data: bytes) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(path: str | Path, text: str) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def write_json(path: str | Path, data: Any) -> Path:
    """Sorted, indented JSON with a trailing newline (stable diffs for DVC metrics)."""
    return write_text(path, json.dumps(data, indent=2, sort_keys=True) + "\n")
