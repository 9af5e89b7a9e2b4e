"""Atomic file writes: every artifact appears whole or not at all.

Each output is written under a hidden temporary name beside its target (`.NAME.tmp<suffix>`, same folder, so the
final `os.replace` is atomic on POSIX) and renamed when complete. An interrupted write leaves the old file, or no
file, plus at most a stray hidden temp file that the next write overwrites. `atomic_dir` does the same for a
folder of files written together (a policy checkpoint).
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any


def temp_path(path: Path, tag: str = "") -> Path:
    """The hidden temp name for `path`; keeps the suffix so tools that pick a format by extension still work.
    `tag` makes it unique to one writer (see `atomic_path`'s `shared`)."""
    return path.with_name(f".{path.stem}.tmp{tag}{path.suffix}")


@contextmanager
def atomic_path(path: str | Path, shared: bool = False) -> Iterator[Path]:
    """Yield a temp path to write `path` through; rename it into place on success, delete it on any error.

    `shared`: several processes may write the same file at once (a content-addressed cache), so each gets a temp
    name of its own; otherwise one could truncate the temp file another is about to rename into place.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = temp_path(path, f"-{secrets.token_hex(4)}" if shared else "")
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextmanager
def atomic_dir(path: str | Path) -> Iterator[Path]:
    """Yield an empty temp folder to fill; on success it replaces the folder `path` as a whole, on any error it is
    deleted. The swap is two renames (the old folder aside, the new one in), so a crash between them leaves no
    `path` but the complete old folder under a hidden `.NAME.old` name."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp, old = temp_path(path), path.with_name(f".{path.name}.old")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir()
    try:
        yield tmp
        shutil.rmtree(old, ignore_errors=True)
        if path.exists():
            path.rename(old)
        tmp.rename(path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    shutil.rmtree(old, ignore_errors=True)


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
