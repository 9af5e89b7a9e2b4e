"""Test helper: kill -9 a stage's main process alone and check that its worker processes die with it."""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path


def children(pid: int) -> list[int]:
    return [int(c) for t in Path(f"/proc/{pid}/task").iterdir() for c in (t / "children").read_text().split()]


def running(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"  # not a zombie
    except (FileNotFoundError, ProcessLookupError):
        return False


def kill_and_list_survivors(proc: subprocess.Popen, workers_expected: int = 2, grace_s: float = 10.0) -> list[int]:
    """Wait until `proc` has its workers, SIGKILL `proc` alone, and return the workers still alive after `grace_s`."""
    try:
        deadline = time.time() + 120
        while time.time() < deadline and len(children(proc.pid)) < workers_expected:
            time.sleep(0.05)
        workers = children(proc.pid)
        assert len(workers) >= workers_expected, f"only {len(workers)} workers started"
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
    deadline = time.time() + grace_s
    alive = workers
    while alive and time.time() < deadline:
        alive = [w for w in workers if running(w)]
        time.sleep(0.05)
    return alive
