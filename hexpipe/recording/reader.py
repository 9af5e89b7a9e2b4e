"""Stream logged steps back out of episode MCAP files, validating every CRC on the way.

Reading never loads a whole file: records are parsed one chunk (~1 MiB) at a time. Every byte of a file is
checked: the footer magic and summary-section CRC up front (this also catches truncation at once), chunk
CRCs as chunks are read, and the data-section CRC when the stream reaches the DataEnd record. Any failure is
a `RecordingError` whose one-line message starts with the file's path.
"""

from __future__ import annotations

import io
import json
import struct
import zlib
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, TypeVar

import numpy as np
from mcap.decoder import DecoderFactory
from mcap.reader import SeekingReader
from mcap.records import Channel, DataEnd, Footer, Message, Schema
from mcap.stream_reader import StreamReader

from hexpipe import sensors as registry
from hexpipe.recording.writer import TOPIC_STEP
from hexpipe.validation import one_line

_MAGIC = b"\x89MCAP0\r\n"
_FOOTER = struct.Struct("<BQQQI")  # opcode, record length, summary_start, summary_offset_start, summary_crc
_FOOTER_OPCODE = 0x02
_BLOCK = 1 << 20

T = TypeVar("T")


class RecordingError(ValueError):
    """An unreadable recording; one line naming the file: 'ep_0003.mcap: truncated or corrupt MCAP (...)'."""


@dataclass(eq=False, slots=True)
class Frame:
    """One logged step of one episode."""

    episode: str  # file stem
    step: int  # index of the logged step within the file (0, 1, ...), not the env step
    sensors: dict[str, np.ndarray]  # sensor name -> reading exactly as logged (e.g. rgb H x W x 3 uint8); absent
    # when not logged at this step or not asked for
    meta: dict[str, Any]  # the step's /step message, plus "terrain" (name) when the file records one


class JsonDecoderFactory(DecoderFactory):
    """Lets `mcap`'s `iter_decoded_messages` decode the JSON topics (/joint_states, /cpg, /step)."""

    def decoder_for(self, message_encoding: str, schema: Schema | None) -> Callable[[bytes], Any] | None:
        return json.loads if message_encoding == "json" else None


def read_metadata(path: Path) -> dict[str, dict[str, str]]:
    """The file's MCAP Metadata records, name -> {key: value}, found via the CRC-checked summary index."""
    path = Path(path)
    with _open(path) as stream:
        _check_tail(path, stream)
        records = _guard(path, lambda: list(SeekingReader(stream, validate_crcs=True).iter_metadata()))
    return {record.name: dict(record.metadata) for record in records}


def count_messages(path: Path) -> dict[str, int]:
    """Messages per topic, from the summary's Statistics record (no message data is read)."""
    path = Path(path)
    with _open(path) as stream:
        _check_tail(path, stream)
        summary = _guard(path, lambda: SeekingReader(stream, validate_crcs=True).get_summary())
    if summary is None or summary.statistics is None:
        raise RecordingError(f"{path}: MCAP has no summary statistics (not written by EpisodeWriter?)")
    counts: dict[str, int] = {}
    for channel_id, count in summary.statistics.channel_message_counts.items():
        channel = summary.channels.get(channel_id)
        if channel is None:
            raise RecordingError(f"{path}: corrupt MCAP summary (statistics name unknown channel {channel_id})")
        counts[channel.topic] = counts.get(channel.topic, 0) + count
    return counts


def iter_frames(path_or_folder: Path, modalities: Sequence[str] | None = None) -> Iterator[Frame]:
    """Yield every logged step of one file, or of a folder's episodes (see `_episode_files`) in sorted name order.

    A step's messages share a log time; a step without a /step message is incomplete and skipped. Only the
    requested sensors (default: every registered one) are decoded. A bad file raises `RecordingError` when reached,
    possibly after its good steps were yielded (the data-section CRC is known only at the end).
    """
    modalities = registry.names() if modalities is None else modalities
    unknown = set(modalities) - set(registry.names())
    if unknown:
        raise ValueError(f"modalities: unknown {sorted(unknown)}; allowed: {sorted(registry.names())}")
    for path in _episode_files(Path(path_or_folder)):
        yield from _iter_file(path, frozenset(modalities))


def _episode_files(path: Path) -> list[Path]:
    """A file, or a folder's episodes: those its manifest lists when it has one (collect's folders), else all."""
    if path.is_dir():
        from hexpipe.recording.manifest import listed_files  # it imports this module

        listed = listed_files(path)
        files = sorted(listed[0]) if listed is not None else sorted(p for p in path.glob("*.mcap") if p.is_file())
        if not files:
            raise RecordingError(f"{path}: no .mcap files in this folder")
        return files
    if not path.is_file():
        raise RecordingError(f"{path}: no such file or folder")
    return [path]


def _iter_file(path: Path, modalities: frozenset[str]) -> Iterator[Frame]:
    metadata = read_metadata(path)  # also validates the tail, so truncation fails before any frame
    terrain = metadata.get("episode", {}).get("terrain") or metadata.get("terrain", {}).get("name")
    by_topic = {registry.get(m).topic: registry.get(m) for m in modalities}
    wanted = {TOPIC_STEP, *by_topic}
    topics: dict[int, str] = {}
    index = 0
    pending_time: int | None = None
    pending: dict[str, bytes] = {}

    def flush() -> Frame | None:
        if TOPIC_STEP not in pending:
            return None
        try:
            meta = json.loads(pending[TOPIC_STEP])
            readings = {sensor.name: sensor.decode(_DECODERS[sensor.kind](pending[topic]))
                        for topic, sensor in by_topic.items() if topic in pending}
        except (ValueError, IndexError, KeyError, TypeError, struct.error) as exc:
            raise RecordingError(f"{path}: bad message at log time {pending_time} ({one_line(exc)})") from None
        if terrain is not None:
            meta.setdefault("terrain", terrain)
        return Frame(episode=path.stem, step=index, sensors=readings, meta=meta)

    seen_data_end = False
    with _open(path) as stream:
        for record in _records(path, stream):
            if isinstance(record, Channel):
                topics[record.id] = record.topic
            elif isinstance(record, Message):
                topic = topics.get(record.channel_id)
                if topic is None:
                    raise RecordingError(f"{path}: corrupt MCAP (message on unknown channel {record.channel_id})")
                if topic not in wanted:
                    continue
                if record.log_time != pending_time:
                    if (frame := flush()) is not None:
                        yield frame
                        index += 1
                    pending_time, pending = record.log_time, {}
                pending[topic] = record.data
            elif isinstance(record, DataEnd):
                seen_data_end = True  # its CRC was checked by StreamReader before yielding it
            elif isinstance(record, Footer) and not seen_data_end:
                raise RecordingError(f"{path}: truncated or corrupt MCAP (no DataEnd record)")
    if (frame := flush()) is not None:
        yield frame


def _records(path: Path, stream: IO[bytes]) -> Iterator[Any]:
    """StreamReader's records with CRC validation, any parse failure turned into a RecordingError."""
    records = StreamReader(stream, validate_crcs=True).records
    while True:
        try:
            record = next(records)
        except StopIteration:
            return
        except Exception as exc:  # the parser raises a zoo: McapError, CRC, struct, zstd, unicode, ...
            raise RecordingError(f"{path}: truncated or corrupt MCAP ({one_line(exc)})") from None
        yield record


def _guard(path: Path, read: Callable[[], T]) -> T:
    """Run an mcap read, turning its failures into a RecordingError."""
    try:
        return read()
    except Exception as exc:
        raise RecordingError(f"{path}: truncated or corrupt MCAP ({one_line(exc)})") from None



class _Bounded:
    """A read-only file view whose reads never ask for more than the file holds.

    A corrupt length field can claim gigabytes; Python's buffered read would allocate that much up front.
    """

    def __init__(self, raw: IO[bytes], size: int) -> None:
        self._raw, self.size, self._pos = raw, size, raw.tell()

    def read(self, n: int | None = -1) -> bytes:
        left = max(self.size - self._pos, 0)
        data = self._raw.read(left if n is None or n < 0 else min(n, left))
        self._pos += len(data)
        return data

    def seek(self, offset: int, whence: int = io.SEEK_SET) -> int:
        self._pos = self._raw.seek(offset, whence)
        return self._pos

    def tell(self) -> int:
        return self._pos

    def seekable(self) -> bool:
        return True


@contextmanager
def _open(path: Path) -> Iterator[_Bounded]:
    """Open an episode file as a `_Bounded` stream at offset 0; failing to open is a RecordingError too."""
    try:
        file = open(path, "rb")  # noqa: SIM115 - closed by the with below; only open() errors are wrapped
    except OSError as exc:
        raise RecordingError(f"{path}: cannot open ({exc.strerror})") from None
    with file:
        size = file.seek(0, io.SEEK_END)
        file.seek(0)
        yield _Bounded(file, size)


def _check_tail(path: Path, stream: _Bounded) -> None:
    """Check the trailing magic, the footer and the summary CRC (what a truncated file lacks); rewind."""
    tail = _FOOTER.size + len(_MAGIC)
    if stream.size < len(_MAGIC) + tail:
        raise RecordingError(f"{path}: truncated or corrupt MCAP ({stream.size} bytes is too short)")
    stream.seek(stream.size - tail)
    raw = stream.read(tail)
    if raw[-len(_MAGIC) :] != _MAGIC:
        raise RecordingError(f"{path}: truncated or corrupt MCAP (no MCAP magic at the end)")
    opcode, length, summary_start, _, summary_crc = _FOOTER.unpack(raw[: _FOOTER.size])
    footer_start = stream.size - tail
    if opcode != _FOOTER_OPCODE or length != _FOOTER.size - 9 or not 0 < summary_start <= footer_start:
        raise RecordingError(f"{path}: truncated or corrupt MCAP (bad footer)")
    if summary_crc == 0:  # the writer chose not to record one
        stream.seek(0)
        return
    crc = 0
    stream.seek(summary_start)
    left = footer_start + _FOOTER.size - 4 - summary_start  # up to and including summary_offset_start
    while left > 0:
        block = stream.read(min(left, _BLOCK))
        crc = zlib.crc32(block, crc)
        left -= len(block)
    if crc != summary_crc:
        raise RecordingError(f"{path}: truncated or corrupt MCAP (summary CRC {crc:#x}, expected {summary_crc:#x})")
    stream.seek(0)


# --- minimal protobuf decoding of the two foxglove messages the frames need (no protobuf runtime required);
# field numbers are those of foxglove.RawImage and foxglove.Grid.


def _fields(buf: bytes) -> dict[int, list[Any]]:
    """Top-level fields of a protobuf message: number -> values (int for varint/fixed, bytes otherwise)."""
    out: dict[int, list[Any]] = {}
    i, n = 0, len(buf)
    while i < n:
        key, i = _varint(buf, i)
        number, wire = key >> 3, key & 7
        if wire == 0:
            value, i = _varint(buf, i)
        elif wire == 5:
            (value,), i = struct.unpack_from("<I", buf, i), i + 4
        elif wire == 1:
            (value,), i = struct.unpack_from("<Q", buf, i), i + 8
        elif wire == 2:
            size, i = _varint(buf, i)
            if i + size > n:
                raise ValueError("protobuf field overruns the message")
            value, i = buf[i : i + size], i + size
        else:
            raise ValueError(f"unsupported protobuf wire type {wire}")
        out.setdefault(number, []).append(value)
    return out


def _varint(buf: bytes, i: int) -> tuple[int, int]:
    value = shift = 0
    while True:
        byte = buf[i]
        i += 1
        value |= (byte & 0x7F) << shift
        if byte < 0x80:
            return value, i
        shift += 7


def _last(fields: dict[int, list[Any]], number: int, default: Any) -> Any:
    values = fields.get(number)
    return values[-1] if values else default


def _decode_image(buf: bytes) -> np.ndarray:
    """foxglove.RawImage (rgb8) -> H x W x 3 uint8."""
    f = _fields(buf)
    width, height, encoding = _last(f, 2, 0), _last(f, 3, 0), bytes(_last(f, 4, b"")).decode()
    step, data = _last(f, 5, 0), _last(f, 6, b"")
    if encoding != "rgb8" or step != 3 * width or len(data) != step * height:
        raise ValueError(f"unsupported image: {encoding} {width}x{height}, step {step}, {len(data)} bytes")
    return np.frombuffer(data, np.uint8).reshape(height, width, 3).copy()


def _decode_grid(buf: bytes) -> np.ndarray:
    """foxglove.Grid with one packed float32 field -> R x C float32 (the writer stored it transposed)."""
    f = _fields(buf)
    columns, row_stride, cell_stride, data = _last(f, 4, 0), _last(f, 6, 0), _last(f, 7, 0), _last(f, 9, b"")
    if cell_stride != 4 or row_stride != 4 * columns or columns == 0 or len(data) % row_stride:
        raise ValueError(f"unsupported grid: {columns} columns, strides {row_stride}/{cell_stride}")
    return np.frombuffer(data, "<f4").reshape(-1, columns).T.astype(np.float32, order="C")


_DECODERS: dict[str, Callable[[bytes], Any]] = {"image": _decode_image, "grid": _decode_grid, "json": json.loads}
