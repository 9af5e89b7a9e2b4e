"""`hexpipe play`: watch one controller on one terrain, as rl-zoo's `enjoy` does for its agents.

One or more seeded episodes of the trained policy (eval.policy_dir), a blind policy, or a fixed gait, through the
same `run_episode` as `hexpipe evaluate` (same controllers, MCAP logging, videos and metrics). Optionally streamed
live to Foxglove: a foxglove-sdk WebSocket server publishes the very topics of the MCAP files (the recording code's
`EpisodeLog` and `EpisodeWriter`, on the server's context), paced at `speed` x real time.
"""

from __future__ import annotations

import ipaddress
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any

from hexpipe.config import ConfigError, Params
from hexpipe.evaluation.controllers import ControllerSpec, Gait, build, gait_label
from hexpipe.evaluation.episodes import EpisodeJob, StepHook, run_episode
from hexpipe.evaluation.suite import load_scenarios
from hexpipe.recording.writer import TOPIC_ROBOT, TOPIC_TERRAIN

LOOPBACK = ("127.0.0.1", "localhost", "::1")
GAP_NS = 1_000_000_000  # between episodes of one live stream: its time keeps increasing (1 s)


class PlayError(ValueError):
    """Nothing to play, or a live server that cannot start; one line saying what to do."""


@dataclass(frozen=True)
class LiveOptions:
    """The live Foxglove view: where the server listens, how fast episodes run, and whether to wait for a viewer."""

    host: str = "127.0.0.1"
    port: int = 8765  # Foxglove's default; 0 picks a free port
    speed: float = 1.0  # sim seconds per wall-clock second
    wait: bool = True  # hold the first step until a viewer subscribes


def exposes_stream(host: str) -> bool:
    """True if binding `host` lets other machines connect (anything but loopback)."""
    if host in LOOPBACK:
        return False
    try:
        return not ipaddress.ip_address(host).is_loopback
    except ValueError:  # a host name: assume it is reachable
        return True


def parse_gait(text: str) -> Gait:
    """'a,b,omega' (rad, rad, rad/s) -> a positive gait, or ConfigError naming the bad value. It may lie outside
    cpg.lower and cpg.upper: a fixed gait runs with the bounds widened to it."""
    parts = [p.strip() for p in text.split(",")]
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise ConfigError(f"--gait {text!r}: expected three numbers a,b,omega (rad, rad, rad/s), e.g. 0.25,0.4,4.71")
    for name, value in zip(("a", "b", "omega"), values, strict=True):
        if not value > 0:
            raise ConfigError(f"--gait: {name}={value:g} must be positive (rad, rad, rad/s)")
    return values  # type: ignore[return-value]


def controller_spec(params: Params, policy: str | None, blind: str | None, gait: str | None) -> ControllerSpec:
    """What to play: --gait, --blind DIR, --policy DIR, or by default the trained policy in eval.policy_dir."""
    if sum(x is not None for x in (policy, blind, gait)) > 1:
        raise PlayError("choose one controller: --policy DIR, --blind DIR or --gait a,b,omega")
    if gait is not None:
        return ControllerSpec("fixed_gait", gait=parse_gait(gait))
    if blind is not None:
        return ControllerSpec("blind", blind, expect_blind=True)
    if policy is None:
        policy = params.eval.policy_dir
        if not Path(policy).is_dir():
            raise PlayError(
                f"no trained policy at {policy} (eval.policy_dir): run the pipeline first (`make repro`), pass "
                "--policy DIR, or watch a fixed gait with --gait a,b,omega"
            )
    return ControllerSpec("policy", policy)


def numbered(path: Path | None, index: int, episodes: int) -> Path | None:
    """`path` for a single episode; `stem_<index>.suffix` when there are several."""
    if path is None or episodes == 1:
        return path
    return path.with_name(f"{path.stem}_{index}{path.suffix}")


def _viewers_listener() -> Any:
    """A foxglove-sdk ServerListener that notes subscriptions (called on the server's thread; only sets flags)."""
    from foxglove.websocket import ServerListener

    class Viewers(ServerListener):
        def __init__(self) -> None:
            self.subscribed = threading.Event()  # any client subscribed to any topic
            self.last_subscribe = 0.0  # time.monotonic() of the latest subscription
            self.resend_static = threading.Event()  # someone (re)subscribed to /robot or /terrain: log them again

        def on_subscribe(self, client: Any, channel: Any) -> None:
            self.last_subscribe = time.monotonic()
            self.subscribed.set()
            if channel.topic in (TOPIC_ROBOT, TOPIC_TERRAIN):
                self.resend_static.set()

    return Viewers()


class LiveStream:
    """A Foxglove WebSocket server (foxglove-sdk's own) for one play session; `hook(job)` streams one episode.

    One `EpisodeWriter` on the server's context carries the whole session and `EpisodeLog` fills it, episode after
    episode, so the live topics and schemas are those of the MCAP files and the channels stay put between episodes
    (a viewer keeps its subscriptions). The URL is announced once every channel exists: a subscription that races
    a channel's advertisement can be refused by the server. The robot and terrain, logged once per episode, are
    logged again whenever a viewer subscribes to them. Use as a context manager: the server stops on exit, also on
    Ctrl-C.
    """

    def __init__(self, options: LiveOptions, echo: Callable[[str], None] = print) -> None:
        if not options.speed > 0 or not math.isfinite(options.speed):
            raise ConfigError(f"--speed {options.speed}: must be a positive number (1 = real time)")
        self.options, self.echo = options, echo
        self.viewers = _viewers_listener()
        self.server: Any = None
        self.writer: Any = None
        self._next_offset_ns = 0
        self._announced = False

    @property
    def url(self) -> str:
        host = self.options.host
        return f"ws://{f'[{host}]' if ':' in host else host}:{self.server.port}"

    def __enter__(self) -> LiveStream:
        import foxglove

        from hexpipe.recording.writer import EpisodeWriter

        context = foxglove.Context()
        try:
            self.server = foxglove.start_server(
                name="hexpipe play", host=self.options.host, port=self.options.port, context=context,
                server_listener=self.viewers,
            )
        except RuntimeError as exc:
            reason = str(exc).removeprefix("FoxgloveError: ")
            raise PlayError(f"cannot start the live server on {self.options.host}:{self.options.port} ({reason}); "
                            "pick another --port") from None
        self.writer = EpisodeWriter(None, {}, context=context)
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        try:
            self.writer.__exit__(exc_type, exc, tb)  # closes the channels
        finally:
            self.server.stop()

    def hook(self, job: EpisodeJob) -> StepHook:
        """The `run_episode` step hook that streams `job`'s episode and paces it."""
        from hexpipe.recording.episode import EpisodeLog

        speed = self.options.speed
        log: EpisodeLog | None = None
        started = 0.0

        def on_step(env: Any, reward: float, info: dict[str, Any], ended: bool) -> None:
            nonlocal log, started
            first_call = log is None  # just after reset
            if log is None:
                log = EpisodeLog(env, None, {}, writer=self.writer, time_offset_ns=self._next_offset_ns)
            elif self.viewers.resend_static.is_set():
                self.viewers.resend_static.clear()
                log.log_static(log.now_ns())
            log.step(reward, force=True)  # the session's first call creates the JSON channels
            if first_call:
                if not self._announced:
                    self._announced = True
                    self.echo(f"live: {self.url} (Foxglove: Open connection; layout layouts/hexpipe_layout.json)")
                    if self.options.wait:
                        self._wait_for_viewer()
                        self.viewers.resend_static.clear()
                        log.log_static(log.now_ns() + 1)
                started = time.monotonic()
            delay = started + info["time"] / speed - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            if ended:
                self._next_offset_ns = log.now_ns() + GAP_NS

        return on_step

    def _wait_for_viewer(self, settle_s: float = 0.3, at_most_s: float = 5.0) -> None:
        """Until a viewer subscribes, then until its subscriptions settle (a client subscribes in one batch)."""
        self.echo(f"waiting for a viewer: in Foxglove, Open connection -> {self.url} (Ctrl-C to stop)")
        while not self.viewers.subscribed.wait(timeout=0.2):  # short waits: Ctrl-C gets through
            pass
        start = time.monotonic()
        while time.monotonic() - self.viewers.last_subscribe < settle_s and time.monotonic() - start < at_most_s:
            time.sleep(0.05)


def play(
    params: Params,
    spec: ControllerSpec,
    terrain: str,
    seed: int,
    episodes: int = 1,
    mcap: Path | None = None,
    video: Path | None = None,
    live: LiveOptions | None = None,
    echo: Callable[[str], None] = print,
) -> list[dict[str, Any]]:
    """Run `episodes` episodes (seeds seed, seed+1, ...) and return their result rows (as in results.csv).

    The terrain and the controller are checked before anything runs (TerrainError, PolicyError, ConfigError).
    """
    if episodes < 1:
        raise ConfigError(f"--episodes {episodes}: must be at least 1")
    (scenario,) = load_scenarios([terrain])
    build(spec, params)  # loads and checks a policy once, before the server starts
    for path in (mcap, video):
        if path is not None and path.is_dir():
            raise PlayError(f"{path}: is a folder; give a file name")
    if video is not None and video.suffix.lower() not in (".mp4", ".webm"):
        raise PlayError(f"--video {video}: use a .mp4 (H.264) or .webm (VP9) file name")
    if mcap is not None and mcap.suffix.lower() != ".mcap":
        raise PlayError(f"--mcap {mcap}: use a .mcap file name")

    # Every control step in the MCAP file, as in the live stream (evaluate keeps every collect.log_every-th).
    params = params.model_copy(update={"collect": params.collect.model_copy(update={"log_every": 1})})
    jobs = [EpisodeJob(scenario, spec, i, seed + i, mcap=numbered(mcap, i, episodes),
                       video=numbered(video, i, episodes)) for i in range(episodes)]
    rows = []
    if live is None:
        for job in jobs:
            rows.append(run_episode(params, job).row)
        return rows
    if exposes_stream(live.host):
        echo(f"warning: --host {live.host} exposes the live stream, unauthenticated, to every machine that can "
             f"reach this one on port {live.port}; the default 127.0.0.1 keeps it on this machine")
    with LiveStream(live, echo) as stream:
        for job in jobs:
            rows.append(run_episode(params, job, on_step=stream.hook(job)).row)
    return rows


def describe(spec: ControllerSpec) -> str:
    if spec.gait is not None:
        return f"fixed gait {gait_label(spec.gait)}"
    return f"{spec.name} from {spec.policy_dir}"


def summary_lines(rows: list[dict[str, Any]]) -> list[str]:
    """The one-screen summary: one line per episode, and the means over episodes when there are several."""
    head = f"{'seed':>6} {'termination':<11} {'distance':>8} {'time':>6} {'CoT':>5} {'a':>5} {'b':>5} {'omega':>5}"
    lines = [head]
    for r in rows:
        lines.append(
            f"{r['seed']:>6} {r['termination']:<11} {r['distance']:>6.2f} m {r['time']:>4.1f} s "
            f"{r['cost_of_transport']:>5.2f} {r['a_mean']:>5.2f} {r['b_mean']:>5.2f} "
            f"{r['omega_mean']:>5.2f}"
        )
    if len(rows) > 1:
        n = len(rows)
        success = sum(bool(r["success"]) for r in rows)
        lines.append(f"{'':>6} {f'{success}/{n} goal':<11} {sum(r['distance'] for r in rows) / n:>6.2f} m "
                     f"{sum(r['time'] for r in rows) / n:>4.1f} s  (means)")
    lines.append("distance: forward progress (m); CoT: cost of transport E/(m g d); a, b (rad) and omega (rad/s): "
                 "episode means")
    return lines
