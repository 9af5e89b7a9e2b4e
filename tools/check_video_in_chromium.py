"""Check that hexpipe's videos play in a browser: headless Chromium loads each file in a <video> element.

Usage: .venv/bin/python tools/check_video_in_chromium.py [VIDEO ...]

Without arguments it writes two short test clips (H.264 MP4 and VP9 WebM, through hexpipe's own writer) plus an
MPEG-4 Part 2 ('mp4v') clip, the format hexpipe used to write, as a negative control that Chromium must refuse.
Each file is loaded by a local HTML page; the page reports readyState, videoWidth/Height and duration, or the media
error, and Chromium prints the page (--dump-dom). Prints one JSON line per file; exits 1 if a hexpipe clip does not
play (or the control does), 2 if Chromium is missing (Debian: `apt-get install chromium`).
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

PAGE = """<!doctype html><html><body><pre id="out">pending</pre><script>
const names = %s, results = {};
function report() {
  if (Object.keys(results).length === names.length)
    document.getElementById("out").textContent = "RESULT " + JSON.stringify(results);
}
for (const name of names) {
  const video = document.createElement("video");
  video.muted = true;
  video.preload = "auto";
  video.onloadeddata = () => {
    results[name] = {plays: video.readyState >= 2, readyState: video.readyState, width: video.videoWidth,
                     height: video.videoHeight, duration: video.duration};
    report();
  };
  video.onerror = () => {
    results[name] = {plays: false, error: video.error && video.error.code, message: video.error && video.error.message};
    report();
  };
  video.src = name;
  document.body.appendChild(video);
}
</script></body></html>
"""

# Headless, no GPU, no network, no updates, no sync, a fresh profile: nothing leaves the machine or persists.
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run", "--allow-file-access-from-files",
         "--virtual-time-budget=10000"]


def chromium() -> str | None:
    return next((p for p in map(shutil.which, ("chromium", "chromium-browser", "google-chrome")) if p), None)


def play_in_chromium(videos: list[Path], browser: str, timeout_s: float = 120) -> dict[str, dict]:
    """{file name: what the <video> element reported} for `videos` (copied next to the page)."""
    with tempfile.TemporaryDirectory(prefix="hexpipe-chromium-") as tmp:
        root = Path(tmp)
        names = []
        for video in videos:
            shutil.copy(video, root / video.name)
            names.append(video.name)
        (root / "page.html").write_text(PAGE % json.dumps(names))
        run = subprocess.run(
            [browser, *FLAGS, f"--user-data-dir={root / 'profile'}", "--dump-dom", (root / "page.html").as_uri()],
            capture_output=True, text=True, timeout=timeout_s,
        )
    found = re.search(r"RESULT (\{.*\})", run.stdout)
    if found is None:
        raise RuntimeError(f"Chromium printed no result (exit {run.returncode}): {run.stderr.strip()[-300:]}")
    return json.loads(found.group(1).replace("&quot;", '"'))


def sample_clips(folder: Path) -> tuple[list[Path], Path]:
    """hexpipe's H.264 and VP9 clips, and an mp4v clip (OpenCV) as the control that must not play."""
    import cv2
    import numpy as np

    from hexpipe.evaluation.video import Mp4Writer, caption

    frames = []
    for i in range(40):
        frame = np.full((240, 320, 3), 90, dtype=np.uint8)
        frame[100:140, 4 * i:4 * i + 40] = (220, 80, 30)
        frames.append(frame)
    clips = []
    for name in ("hexpipe.mp4", "hexpipe.webm"):
        with Mp4Writer(folder / name, fps=20) as writer:
            for i, frame in enumerate(frames):
                writer.add(frame, caption("flat", i / 20, (0.25, 0.4, 4.71)))
        clips.append(folder / name)
    control = folder / "control_mp4v.mp4"
    legacy = cv2.VideoWriter(str(control), cv2.VideoWriter_fourcc(*"mp4v"), 20, (320, 240))
    for frame in frames:
        legacy.write(frame)
    legacy.release()
    return clips, control


def main(argv: list[str]) -> int:
    browser = chromium()
    if browser is None:
        print("chromium not found (Debian: apt-get install chromium)", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        if argv:
            videos, control = [Path(a) for a in argv], None
        else:
            videos, control = sample_clips(Path(tmp))
        results = play_in_chromium([*videos, *([control] if control else [])], browser)
    ok = True
    for video in videos:
        row = results.get(video.name, {"plays": False, "error": "no report"})
        print(json.dumps({"file": str(video), **row}))
        ok &= bool(row["plays"])
    if control is not None:
        row = results.get(control.name, {})
        print(json.dumps({"file": "control (mp4v, must not play)", **row}))
        ok &= not row.get("plays", True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
