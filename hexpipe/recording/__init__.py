"""Episode recording: MCAP files written during rollouts and read back for training and inspection.

`EpisodeWriter` logs one episode per file with Foxglove's well-known schemas (open it in Foxglove with
layouts/hexpipe_layout.json); `iter_frames` streams the logged sensor frames back, validating CRCs.
"""

from hexpipe.recording.reader import (
    Frame,
    JsonDecoderFactory,
    RecordingError,
    count_messages,
    iter_frames,
    read_metadata,
)
from hexpipe.recording.writer import BoxLike, EpisodeWriter, HeightfieldLike

__all__ = [
    "BoxLike",
    "EpisodeWriter",
    "Frame",
    "HeightfieldLike",
    "JsonDecoderFactory",
    "RecordingError",
    "count_messages",
    "iter_frames",
    "read_metadata",
]
