"""Where outputs may go: names made safe for paths, containment in an output folder, writability up front.

Every name that comes from user input (a terrain's file stem, a scenario name) passes through `safe_name` before it
names a file or folder, and code that deletes old outputs first checks `inside` its output folder: a terrain file
called `...yaml` (stem `..`) must not name the parent folder. `check_writable` runs at the start of a stage, so a
read-only folder is a one-line error before minutes of work, not a traceback after them.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]")
MAX_NAME = 100  # characters; well under every filesystem's limit, with room for prefixes and suffixes


class OutputError(ValueError):
    """An output folder that cannot be written; one line naming it."""


def safe_name(text: str, fallback: str = "unnamed") -> str:
    """A single path component from any text: only letters, digits, `_`, `-` and inner dots; never `.`, `..` or
    hidden (no leading dot), never empty, at most MAX_NAME characters. Distinct readable names stay distinct."""
    name = _UNSAFE.sub("_", text).lstrip(".")[:MAX_NAME].rstrip(".")
    return name or fallback


def inside(path: str | Path, root: str | Path) -> bool:
    """Whether `path` (after resolving `..` and links) lies within folder `root`."""
    return Path(path).resolve().is_relative_to(Path(root).resolve())


def check_writable(*folders: str | Path) -> None:
    """Create each folder and prove a file can be written and removed there; `OutputError` otherwise."""
    for folder in folders:
        folder = Path(folder)
        try:
            folder.mkdir(parents=True, exist_ok=True)
            fd, probe = tempfile.mkstemp(prefix=".hexpipe-write-test-", dir=folder)
            os.close(fd)
            os.unlink(probe)
        except OSError as exc:
            reason = exc.strerror or exc.__class__.__name__
            raise OutputError(f"{folder}: cannot write outputs here ({reason})") from None
