"""The rollout folder's manifest: which episode files make the dataset, with their size and content hash.

collect writes `manifest.json` (atomically, after every finished episode) and trusts a listed file only if its byte
count and BLAKE2b hash still match, so a file truncated or corrupted in place is collected again. Readers of a
folder (train-vae) take exactly the listed files: a stray `.mcap` copied in is reported and left out. A manifest
of the wrong shape is a one-line `ManifestError`.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from hexpipe.atomic import write_text
from hexpipe.recording.reader import RecordingError
from hexpipe.validation import format_validation_error

MANIFEST = "manifest.json"
_BLOCK = 1 << 20


class ManifestError(RecordingError):
    """A manifest that is not JSON or not of collect's shape; one line naming the file."""


class EpisodeRow(BaseModel):
    """One finished episode; the figures beyond these (distance, termination, ...) are kept as they are."""

    model_config = ConfigDict(extra="allow", frozen=True)

    index: int = Field(ge=0)
    file: str = Field(pattern=r"^[A-Za-z0-9_.-]+\.mcap$")  # a plain file name inside the folder
    frames: int = Field(ge=0)
    bytes: int = Field(ge=0)
    digest: str = Field(pattern=r"^[0-9a-f]{32}$")  # BLAKE2b-128 of the file's bytes


class Manifest(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    signature: str
    episodes: list[EpisodeRow]


def file_digest(path: Path) -> str:
    """BLAKE2b-128 of a file, read in 1 MiB blocks (~1 GB/s: a 100 MB dataset checks in a tenth of a second)."""
    digest = hashlib.blake2b(digest_size=16)
    with open(path, "rb") as f:
        while block := f.read(_BLOCK):
            digest.update(block)
    return digest.hexdigest()


def _parse(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (ValueError, UnicodeDecodeError):
        raise ManifestError(f"{path}: not a JSON manifest; delete it to collect afresh") from None


def read_signature(folder: Path) -> str | None:
    """The signature a folder's manifest was made under; None without a manifest."""
    path = Path(folder) / MANIFEST
    if not path.is_file():
        return None
    data = _parse(path)
    if not isinstance(data, dict) or not isinstance(data.get("signature"), str):
        raise ManifestError(f"{path}: not a collect manifest (no 'signature'); delete it to collect afresh")
    return data["signature"]


def read_manifest(folder: Path) -> Manifest | None:
    """The validated manifest of `folder`; None without one."""
    path = Path(folder) / MANIFEST
    if not path.is_file():
        return None
    try:
        return Manifest.model_validate(_parse(path))
    except ValidationError as exc:
        reason = format_validation_error(exc, Manifest, str(path))
        raise ManifestError(f"{reason}; delete it to collect afresh") from None


def write_manifest(folder: Path, signature: str, rows: list[dict[str, Any]]) -> None:
    """Rewrite the manifest atomically, rows in episode order."""
    episodes = sorted(rows, key=lambda r: r["index"])
    write_text(Path(folder) / MANIFEST, json.dumps({"signature": signature, "episodes": episodes}, indent=1))


def check_file(folder: Path, row: EpisodeRow) -> str | None:
    """Why a listed file cannot be trusted ('missing', 'truncated: ...', 'changed since written'); None if intact."""
    path = Path(folder) / row.file
    if not path.is_file():
        return "missing"
    size = path.stat().st_size
    if size != row.bytes:
        return f"{size} bytes, the manifest says {row.bytes}"
    if file_digest(path) != row.digest:
        return "its bytes changed since it was written"
    return None


def listed_files(folder: Path) -> tuple[list[Path], list[Path]] | None:
    """(the manifest's files, the `.mcap` files it does not list) for a folder with a manifest; None without one.

    A listed file that is missing or of the wrong size is a `RecordingError` (collect repairs it)."""
    manifest = read_manifest(folder)
    if manifest is None:
        return None
    folder = Path(folder)
    files = []
    for row in manifest.episodes:
        path = folder / row.file
        if not path.is_file() or path.stat().st_size != row.bytes:
            problem = "missing" if not path.is_file() else "truncated or grown"
            raise RecordingError(f"{path}: listed in {folder / MANIFEST} but {problem}; rerun `hexpipe collect`")
        files.append(path)
    listed = {p.name for p in files}
    extras = sorted(p for p in folder.glob("*.mcap") if p.is_file() and p.name not in listed)
    return files, extras
