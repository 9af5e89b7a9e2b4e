"""Episode videos that play in a browser: H.264 in MP4 (yuv420p, moov atom first) or VP9 in WebM.

Frames are piped to the ffmpeg binary that the `imageio-ffmpeg` wheel ships (built with libx264 and libvpx), so
nothing is needed from the system. The container follows the file's extension. The file is written under a hidden
temporary name (hexpipe.atomic) and appears under its final name only once it decodes again (OpenCV reads it back,
a second decoder); on any error the temporary file is removed. Frames can carry a caption (time, terrain, CPG
parameters) drawn with OpenCV.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import subprocess
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from hexpipe.atomic import temp_path

# Per container: ffmpeg output options. H.264 High profile in yuv420p is what every browser decodes; +faststart
# moves the index (moov) before the data so playback starts before the whole file has loaded. VP9 with -b:v 0 is
# constant quality. One encoder thread: evaluate already runs one worker per core.
CODECS: dict[str, list[str]] = {
    ".mp4": ["-c:v", "libx264", "-preset", "veryfast", "-crf", "23", "-pix_fmt", "yuv420p",
             "-movflags", "+faststart"],
    ".webm": ["-c:v", "libvpx-vp9", "-crf", "34", "-b:v", "0", "-deadline", "realtime", "-cpu-used", "8",
              "-pix_fmt", "yuv420p"],
}


class VideoError(RuntimeError):
    """A video that could not be encoded, or read back; one line naming the file."""


def ffmpeg_exe() -> str:
    """The ffmpeg binary shipped inside the imageio-ffmpeg wheel."""
    import imageio_ffmpeg

    return imageio_ffmpeg.get_ffmpeg_exe()


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


def probe(path: Path) -> dict[str, Any]:
    """The first video stream as ffmpeg reports it: codec, pix_fmt, width, height (px), fps, frames, duration (s).

    Decodes the whole file (`-f null`), so a broken stream shows up as fewer frames or a VideoError.
    """
    run = subprocess.run([ffmpeg_exe(), "-hide_banner", "-nostdin", "-i", str(path), "-map", "0:v:0", "-f", "null",
                          "-"], capture_output=True, text=True, timeout=120)
    stream = re.search(r"Stream #0:0.*?: Video: (\w+).*?, (\w+)(?:\([^)]*\))?, (\d+)x(\d+)", run.stderr)
    if run.returncode != 0 or stream is None:
        last = (run.stderr.strip().splitlines() or ["no output"])[-1]
        raise VideoError(f"{path}: ffmpeg cannot read it ({last})")
    fps = re.search(r"([\d.]+) fps", run.stderr)
    frames = re.findall(r"frame=\s*(\d+)", run.stderr)
    duration = re.search(r"Duration: (\d+):(\d+):([\d.]+)", run.stderr)
    h, m, s = duration.groups() if duration else ("0", "0", "nan")
    return {"codec": stream.group(1), "pix_fmt": stream.group(2), "width": int(stream.group(3)),
            "height": int(stream.group(4)), "fps": float(fps.group(1)) if fps else math.nan,
            "frames": int(frames[-1]) if frames else 0, "duration": 3600 * int(h) + 60 * int(m) + float(s)}


def top_level_boxes(path: Path) -> list[str]:
    """The MP4 file's top-level box types in order (e.g. ftyp, moov, mdat: 'faststart' puts moov before mdat)."""
    boxes, data = [], Path(path).read_bytes()
    at = 0
    while at + 8 <= len(data):
        size, kind = int.from_bytes(data[at:at + 4], "big"), data[at + 4:at + 8].decode("latin-1")
        if size == 1:  # 64-bit size follows the type
            size = int.from_bytes(data[at + 8:at + 16], "big")
        boxes.append(kind)
        if size < 8:
            break
        at += size
    return boxes


def caption(terrain: str, time_s: float, cpg: Sequence[float]) -> list[str]:
    """The overlay lines: time (s), terrain, and the CPG parameters a, b (rad) and omega (rad/s)."""
    a, b, omega = (float(v) for v in cpg)
    return [f"t {time_s:5.2f} s  {terrain}", f"a {a:.2f}  b {b:.2f}  omega {omega:.2f}"]


def overlay(rgb: np.ndarray, lines: Sequence[str]) -> np.ndarray:
    """A copy of `rgb` with `lines` written top left, white on a dark band (readable on any terrain)."""
    import cv2

    out = np.ascontiguousarray(rgb).copy()
    scale = max(out.shape[0] / 480, 0.35)
    step = int(22 * scale) + 4
    band = out[: step * len(lines) + 6]
    band[:] = (band * 0.45).astype(np.uint8)
    for i, text in enumerate(lines):
        cv2.putText(out, text, (6, step * (i + 1)), cv2.FONT_HERSHEY_SIMPLEX, 0.9 * scale, (255, 255, 255), 1,
                    cv2.LINE_AA)
    return out


class Mp4Writer:
    """RGB frames (H, W, 3) uint8 -> a browser-playable video at `path` (.mp4: H.264, .webm: VP9), `fps` frames/s.

    Use as a context manager; `add(frame, lines)` draws `lines` on the frame first. On a clean exit the file is
    read back (OpenCV) and renamed into place; on an error nothing appears at `path`.
    """

    def __init__(self, path: Path, fps: float):
        self.path, self.fps = Path(path), fps
        if self.path.suffix.lower() not in CODECS:
            raise VideoError(f"{self.path}: unsupported video type; use .mp4 (H.264) or .webm (VP9)")
        self.tmp = temp_path(self.path)  # same suffix: ffmpeg picks the container from it
        self.frames = 0  # written
        self.decoded = 0  # read back by cv2.VideoCapture after closing
        self._process: subprocess.Popen | None = None
        self._size: tuple[int, int] | None = None
        self._log = tempfile.TemporaryFile()  # noqa: SIM115 - ffmpeg's stderr; closed in __exit__

    def __enter__(self) -> Mp4Writer:
        return self

    def add(self, rgb: np.ndarray | None, lines: Sequence[str] = ()) -> None:
        if rgb is None:
            return
        if rgb.dtype != np.uint8 or rgb.ndim != 3 or rgb.shape[2] != 3:
            raise ValueError(f"video frames must be H x W x 3 uint8, got {rgb.shape} {rgb.dtype}")
        if lines:
            rgb = overlay(rgb, lines)
        height, width = rgb.shape[:2]
        if self._process is None:
            self._start(width, height)
        elif (width, height) != self._size:
            raise ValueError(f"video frame size changed from {self._size} to {(width, height)}")
        try:
            self._process.stdin.write(np.ascontiguousarray(rgb).tobytes())
        except BrokenPipeError:
            raise VideoError(f"{self.path}: ffmpeg stopped while encoding ({self._last_log()})") from None
        self.frames += 1

    def _start(self, width: int, height: int) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._size = (width, height)
        cmd = [ffmpeg_exe(), "-hide_banner", "-nostdin", "-loglevel", "error", "-y",
               "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{width}x{height}", "-r", f"{self.fps:g}", "-i", "-",
               "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",  # yuv420p needs even sides
               *CODECS[self.path.suffix.lower()], "-threads", "1", str(self.tmp)]
        # Its own session: Ctrl-C reaches Python, which ends the file; if Python dies, ffmpeg sees EOF and exits.
        self._process = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=self._log,
                                         start_new_session=True)

    def _last_log(self) -> str:
        self._log.seek(0)
        lines = self._log.read().decode(errors="replace").strip().splitlines()
        return lines[-1] if lines else "no message"

    def _finish(self) -> None:
        """Close ffmpeg's input, wait for it, check the file decodes, rename it into place."""
        with contextlib.suppress(BrokenPipeError):
            self._process.stdin.close()
        code = self._process.wait()
        if code != 0:
            raise VideoError(f"{self.path}: ffmpeg failed with exit code {code} ({self._last_log()})")
        self.decoded = count_frames(self.tmp)
        if self.decoded == 0:
            raise VideoError(f"{self.path}: wrote {self.frames} frames but none read back")
        os.replace(self.tmp, self.path)

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            if self._process is not None and exc_type is None:
                self._finish()
        finally:
            if self._process is not None and self._process.poll() is None:
                self._process.kill()
                self._process.wait()
            self.tmp.unlink(missing_ok=True)
            self._log.close()
