"""Browser-playable episode videos: codec, pixel format, index placement, captions, atomic writes, Chromium."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from hexpipe.evaluation.video import (
    Mp4Writer,
    VideoError,
    caption,
    count_frames,
    overlay,
    probe,
    top_level_boxes,
)

ROOT = Path(__file__).resolve().parents[1]


def frames(n: int = 30, size: tuple[int, int] = (240, 320)) -> list[np.ndarray]:
    rng = np.random.default_rng(0)
    return [rng.integers(0, 256, (*size, 3), dtype=np.uint8) for _ in range(n)]


@pytest.mark.parametrize(("name", "codec"), [("ep.mp4", "h264"), ("ep.webm", "vp9")])
def test_videos_are_h264_or_vp9_in_yuv420p_and_decode_fully(tmp_path, name, codec):
    with Mp4Writer(tmp_path / name, fps=20) as writer:
        for i, frame in enumerate(frames()):
            writer.add(frame, caption("single_block", i / 20, (0.25, 0.4, 4.71)))
    info = probe(tmp_path / name)
    assert (info["codec"], info["pix_fmt"], info["width"], info["height"]) == (codec, "yuv420p", 320, 240)
    assert info["frames"] == 30 and info["fps"] == 20 and info["duration"] == pytest.approx(1.5, abs=0.06)
    assert writer.decoded == count_frames(tmp_path / name) == 30  # OpenCV, a second decoder, reads them all
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]  # no temporary file left


def test_mp4_puts_its_index_first_so_browsers_start_playing_early(tmp_path):
    with Mp4Writer(tmp_path / "ep.mp4", fps=20) as writer:
        for frame in frames(10):
            writer.add(frame)
    boxes = top_level_boxes(tmp_path / "ep.mp4")
    assert boxes[0] == "ftyp" and boxes.index("moov") < boxes.index("mdat")


def test_odd_frame_sizes_are_padded_to_even_for_yuv420p(tmp_path):
    with Mp4Writer(tmp_path / "odd.mp4", fps=10) as writer:
        for frame in frames(5, size=(121, 161)):
            writer.add(frame)
    info = probe(tmp_path / "odd.mp4")
    assert (info["width"], info["height"], info["frames"]) == (162, 122, 5)


def test_the_caption_is_drawn_in_a_band_at_the_top_only():
    rgb = np.full((240, 320, 3), 200, dtype=np.uint8)
    lines = caption("wide_block", 3.25, (0.3, 0.45, 6.2))
    assert lines == ["t  3.25 s  wide_block", "a 0.30  b 0.45  omega 6.20"]
    out = overlay(rgb, lines)
    changed = np.flatnonzero((out != rgb).any(axis=(1, 2)))
    assert changed.min() == 0 and changed.max() < 60  # two lines of text on a dimmed band, nothing below
    assert (out[:changed.max()] == 255).any()  # white text
    assert np.array_equal(rgb, np.full((240, 320, 3), 200, dtype=np.uint8))  # the input is left alone


def test_an_error_while_filming_leaves_no_file(tmp_path):
    with pytest.raises(RuntimeError, match="boom"), Mp4Writer(tmp_path / "ep.mp4", fps=20) as writer:
        writer.add(frames(1)[0])
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(VideoError, match=r"use \.mp4 \(H\.264\) or \.webm"):
        Mp4Writer(tmp_path / "ep.avi", fps=20)
    with pytest.raises(VideoError, match="ffmpeg cannot read it"):
        (tmp_path / "junk.mp4").write_bytes(b"not a video")
        probe(tmp_path / "junk.mp4")


def test_an_existing_video_is_replaced_only_when_the_new_one_is_complete(tmp_path):
    path = tmp_path / "ep.mp4"
    with Mp4Writer(path, fps=20) as writer:
        for frame in frames(8):
            writer.add(frame)
    with pytest.raises(KeyboardInterrupt), Mp4Writer(path, fps=20) as writer:
        writer.add(frames(1)[0])
        raise KeyboardInterrupt
    assert probe(path)["frames"] == 8


def _chromium_tool():
    spec = importlib.util.spec_from_file_location("check_video", ROOT / "tools" / "check_video_in_chromium.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.skipif(_chromium_tool().chromium() is None, reason="no chromium (Debian: apt-get install chromium)")
def test_headless_chromium_plays_both_formats_and_refuses_the_old_mp4v(tmp_path):
    tool = _chromium_tool()
    clips, control = tool.sample_clips(tmp_path)
    results = tool.play_in_chromium([*clips, control], tool.chromium())
    for clip in clips:
        row = results[clip.name]
        assert row["plays"] and (row["width"], row["height"]) == (320, 240) and row["duration"] == 2, row
    assert not results[control.name]["plays"]  # the negative control: the test can fail
