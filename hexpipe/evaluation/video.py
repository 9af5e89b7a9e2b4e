"""MP4 episode videos written with OpenCV; the file appears under its final name only once it reopens with frames."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np


class VideoError(RuntimeError):
    """OpenCV could not write, or read back, a video."""


def count_frames(path: Path) -> int:
    """Frames OpenCV decodes from `path` (0 if it does not open)."""
    import cv2

    capture = cv2.VideoCapture(str(path))
    try:
        if not capture.isOpened():
            return 0
        frames = 0
        while capture.grab():
            frames += 1
        return frames
    finally:
        capture.release()


class Mp4Writer:
    """RGB frames (H, W, 3) uint8 -> `path` ('mp4v', `fps` frames/s); use as a context manager.

    Frames go to `.<name>.tmp.mp4` (OpenCV picks the container from the extension); on a clean exit the file is
    reopened and checked to decode, then renamed. On an error the temporary file is removed.
    """

    def __init__(self, path: Path, fps: float):
        self.path, self.fps = Path(path), fps
        self.tmp = self.path.with_name(f".{self.path.stem}.tmp.mp4")
        self.frames = 0  # written
        self.decoded = 0  # read back by cv2.VideoCapture after closing
        self._writer = None

    def __enter__(self) -> Mp4Writer:
        return self

    def add(self, rgb: np.ndarray | None) -> None:
        import cv2

        if rgb is None:
            return
        if self._writer is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            height, width = rgb.shape[:2]
            self._writer = cv2.VideoWriter(str(self.tmp), cv2.VideoWriter_fourcc(*"mp4v"), self.fps, (width, height))
            if not self._writer.isOpened():
                raise VideoError(f"{self.path}: OpenCV cannot open an mp4v writer")
        self._writer.write(np.ascontiguousarray(rgb[:, :, ::-1]))  # OpenCV wants BGR
        self.frames += 1

    def __exit__(self, exc_type, exc, tb) -> None:
        if self._writer is not None:
            self._writer.release()
        if exc_type is not None or self.frames == 0:
            self.tmp.unlink(missing_ok=True)
            return
        self.decoded = count_frames(self.tmp)
        if self.decoded == 0:
            self.tmp.unlink(missing_ok=True)
            raise VideoError(f"{self.path}: wrote {self.frames} frames but none read back")
        os.replace(self.tmp, self.path)
