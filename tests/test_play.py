"""`hexpipe play`: the summary, its files, the live Foxglove server (checked with a WebSocket client), and errors."""

import json
import os
import queue
import re
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from hexpipe import __version__
from hexpipe.cli import app
from hexpipe.config import ConfigError, load_params
from hexpipe.evaluation.controllers import ControllerSpec
from hexpipe.evaluation.video import probe
from hexpipe.play import LiveOptions, PlayError, controller_spec, exposes_stream, parse_gait, play
from hexpipe.recording.reader import count_messages, read_metadata

websockets = pytest.importorskip("websockets.sync.client")

ROOT = Path(__file__).resolve().parents[1]
runner = CliRunner()
GAIT = "0.4,0.5,4.712389"
SHORT = ["task.time_limit=1.0"]  # 20 control steps


def short_params(*extra: str):
    return load_params(ROOT / "params.yaml", [*SHORT, *extra])


def test_version_and_short_help():
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0 and result.output.strip() == f"hexpipe {__version__}"
    short, long = runner.invoke(app, ["-h"]), runner.invoke(app, ["--help"])
    assert short.exit_code == 0 and short.output == long.output and "play" in short.output
    assert runner.invoke(app, ["play", "-h"]).exit_code == 0


def test_play_a_fixed_gait_prints_the_summary_and_writes_mcap_and_video(tmp_path):
    args = ["play", "--params", str(ROOT / "params.yaml"), "--gait", GAIT, "--terrain", "flat", "--seed", "7",
            "--mcap", str(tmp_path / "ep.mcap"), "--video", str(tmp_path / "ep.mp4")]
    for override in SHORT:
        args += ["--set", override]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    row = next(line for line in result.output.splitlines() if line.strip().startswith("7 "))
    seed, termination, distance, _, time_s, _, cot, a, b, omega = row.split()
    assert (seed, termination, time_s) == ("7", "time_limit", "1.0")
    assert 0 < float(distance) < 1 and float(cot) > 0
    assert (float(a), float(b), float(omega)) == pytest.approx((0.4, 0.5, 4.71), abs=0.005)
    assert read_metadata(tmp_path / "ep.mcap")["episode"]["seed"] == "7"
    assert count_messages(tmp_path / "ep.mcap")["/step"] == 21  # reset + 20 steps
    assert probe(tmp_path / "ep.mp4")["frames"] == 21
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ep.mcap", "ep.mp4"]  # no temporary files left


def test_several_episodes_get_consecutive_seeds_and_numbered_files(tmp_path):
    params = short_params("task.time_limit=0.5")
    spec = ControllerSpec("fixed_gait", gait=(0.3, 0.3, 4.0))
    rows = play(params, spec, "flat", seed=3, episodes=2, mcap=tmp_path / "run.mcap", echo=lambda _: None)
    assert [r["seed"] for r in rows] == [3, 4]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run_0.mcap", "run_1.mcap"]


def test_without_a_trained_policy_one_line_says_what_to_do(tmp_path):
    result = runner.invoke(app, ["play", "--params", str(ROOT / "params.yaml"),
                                 "--set", f"eval.policy_dir={tmp_path / 'none'}"])
    assert result.exit_code == 2
    (line,) = result.output.strip().splitlines()[-1:]
    assert "no trained policy" in line and "make repro" in line and "--gait" in line
    assert "Traceback" not in result.output


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--gait", "0.4,0.5"], "expected three numbers"),
        (["--gait", "0.4,0,4.7"], "b=0 must be positive"),
        (["--gait", GAIT, "--terrain", "nowhere"], "unknown terrain 'nowhere'"),
        (["--gait", GAIT, "--video", "x.avi"], ".mp4 (H.264) or .webm"),
        (["--gait", GAIT, "--blind", "somewhere"], "choose one controller"),
        (["--gait", GAIT, "--live", "--speed", "0"], "--speed 0.0: must be a positive number"),
        (["--blind", "no/such/dir"], "no trained policy at no/such/dir"),
    ],
)
def test_bad_play_options_are_one_line(args, expected):
    result = runner.invoke(app, ["play", "--params", str(ROOT / "params.yaml"), *args])
    assert result.exit_code == 2, result.output
    assert expected in result.output and "Traceback" not in result.output
    assert len(result.output.strip().splitlines()) <= 2  # the "play: ..." line at most, then the error


def test_gait_parsing_and_controller_choice():
    params = short_params()
    assert parse_gait(" 0.25, 0.4 ,4.71") == (0.25, 0.4, 4.71)
    assert parse_gait("0.25,0.4,9") == (0.25, 0.4, 9.0)  # above the ceilings: the bounds are widened to it
    assert parse_gait("0.05,0.1,1.6") == (0.05, 0.1, 1.6)  # below the floors: the paper's gaits may be watched
    with pytest.raises(ConfigError, match="a=0 must be positive"):
        parse_gait("0,0.4,4.71")
    assert controller_spec(params, None, None, "0.25,0.4,4.71").gait == (0.25, 0.4, 4.71)
    assert controller_spec(params, None, "d", None) == ControllerSpec("blind", "d", expect_blind=True)


def test_only_loopback_keeps_the_stream_private():
    assert not any(map(exposes_stream, ("127.0.0.1", "localhost", "::1", "127.0.0.2")))
    assert all(map(exposes_stream, ("0.0.0.0", "192.168.1.5", "::", "myhost.example")))


def test_a_host_that_exposes_the_stream_warns_and_a_bad_one_is_one_line():
    said = []
    with pytest.raises(PlayError, match=r"cannot start the live server on 256\.0\.0\.1:0 .*pick another --port"):
        play(short_params(), ControllerSpec("fixed_gait", gait=(0.3, 0.3, 4.0)), "flat", seed=0,
             live=LiveOptions(host="256.0.0.1", port=0), echo=said.append)
    assert said and said[0].startswith("warning: --host 256.0.0.1 exposes the live stream")


def server_gone(url: str, patience_s: float = 10.0) -> bool:
    """True once nothing listens at `url` (the SDK's stop() closes the socket asynchronously, within ms)."""
    host, port = url.removeprefix("ws://").rsplit(":", 1)
    deadline = time.monotonic() + patience_s
    while time.monotonic() < deadline:
        try:
            socket.create_connection((host, int(port)), timeout=1).close()
        except OSError:
            return True
        time.sleep(0.1)
    return False


class FoxgloveClient:
    """Just enough of the Foxglove WebSocket protocol: subscribe to every advertised channel, record the messages."""

    def __init__(self) -> None:
        self.channels: dict[int, dict] = {}  # channel id -> advertisement
        self.advertised: list[str] = []  # topics, in order, repeats included
        self.by_subscription: dict[int, str] = {}
        self.stamps: dict[str, list[int]] = {}  # topic -> log times (ns) of the messages received
        self.first_payload: dict[str, bytes] = {}
        self.server_name = ""

    def run(self, url: str) -> None:
        """Until the server closes the connection."""
        from websockets.exceptions import ConnectionClosed

        # foxglove-sdk 0.30 speaks (and the Foxglove app offers) the subprotocol "foxglove.sdk.v1"
        with websockets.connect(url, subprotocols=["foxglove.sdk.v1"], open_timeout=10) as ws:
            try:
                while True:
                    self._handle(ws, ws.recv(timeout=60))
            except ConnectionClosed:
                pass

    def _handle(self, ws, frame) -> None:
        if isinstance(frame, bytes):
            opcode, subscription, stamp = struct.unpack_from("<BIQ", frame)
            if opcode == 1:  # message data
                topic = self.by_subscription[subscription]
                self.stamps.setdefault(topic, []).append(stamp)
                self.first_payload.setdefault(topic, frame[13:])
            return
        message = json.loads(frame)
        if message["op"] == "serverInfo":
            self.server_name = message["name"]
        elif message["op"] == "advertise":
            subscriptions = []
            for channel in message["channels"]:
                self.channels[channel["id"]] = channel
                self.advertised.append(channel["topic"])
                sub = len(self.by_subscription)
                self.by_subscription[sub] = channel["topic"]
                subscriptions.append({"id": sub, "channelId": channel["id"]})
            ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))


def test_live_streams_the_recording_topics_to_a_websocket_client_and_stops_at_the_end(tmp_path):
    from hexpipe.recording.writer import TOPIC_CPG, TOPIC_ROBOT, TOPIC_STEP, TOPIC_TERRAIN

    said: queue.Queue[str] = queue.Queue()
    params = short_params("task.time_limit=0.5")  # 10 control steps
    spec = ControllerSpec("fixed_gait", gait=(0.4, 0.5, 4.712389))
    result: dict = {}

    def run() -> None:
        try:
            result["rows"] = play(params, spec, "single_block", seed=1, episodes=2, mcap=tmp_path / "same.mcap",
                                  live=LiveOptions(port=0, speed=4.0), echo=said.put)
        except BaseException as exc:  # reported below
            result["error"] = exc

    player = threading.Thread(target=run, daemon=True)
    player.start()
    try:
        url = None
        while url is None:
            line = said.get(timeout=60)
            url = (re.search(r"ws://127\.0\.0\.1:\d+", line) or [None])[0]
        client = FoxgloveClient()
        client.run(url)  # returns when the server closes the connection after the last episode
    finally:
        player.join(timeout=60)
    assert not player.is_alive() and "error" not in result, result.get("error")
    assert client.server_name == "hexpipe play"

    # The same topics and schemas as the MCAP files of the same episodes, each channel advertised once.
    recorded = count_messages(tmp_path / "same_0.mcap")
    assert sorted(client.advertised) == sorted(recorded)
    advertised = {c["topic"]: c for c in client.channels.values()}
    assert advertised[TOPIC_ROBOT]["schemaName"] == "foxglove.SceneUpdate"
    assert advertised[TOPIC_CPG]["encoding"] == "json"
    assert all(client.stamps.get(topic) for topic in recorded)
    # It waited for the viewer: every control step arrived; only the first reset frame, logged as the channels
    # were created (before anyone could subscribe), did not. Time keeps increasing from episode to episode.
    assert recorded[TOPIC_STEP] == 11
    steps = client.stamps[TOPIC_STEP]
    assert len(steps) == 2 * 11 - 1 and steps == sorted(set(steps))
    assert len(client.stamps[TOPIC_ROBOT]) >= 2 and len(client.stamps[TOPIC_TERRAIN]) >= 2  # each episode
    assert json.loads(client.first_payload[TOPIC_CPG])["b"] == pytest.approx(0.5)
    assert [r["seed"] for r in result["rows"]] == [1, 2]
    assert server_gone(url)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_ctrl_c_stops_the_live_server_and_leaves_no_partial_files(tmp_path):
    cmd = [sys.executable, "-m", "hexpipe.cli", "play", "--params", str(ROOT / "params.yaml"), "--gait", GAIT,
           "--live", "--port", "0", "--mcap", str(tmp_path / "ep.mcap"), "--video", str(tmp_path / "ep.mp4")]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    # A terminal's Ctrl-C: SIGINT at its default, also when the tests run as a background job (a non-interactive
    # shell starts those with SIGINT ignored, the child would inherit that, and Python then never raises
    # KeyboardInterrupt).
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        lines = []
        for line in proc.stderr:  # blocks until it waits for a viewer (nobody connects)
            lines.append(line)
            if "waiting for a viewer" in line:
                break
        url = re.search(r"ws://127\.0\.0\.1:\d+", "".join(lines))[0]
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, err
    assert "stopped" in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []  # the unfinished MCAP and video were removed
    assert server_gone(url)
