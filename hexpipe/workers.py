"""Worker processes that never outlive their stage, and a Ctrl-C that stops a stage at once and keeps its work.

* `die_with_parent`: a forked worker asks Linux to SIGKILL it when its parent dies (PR_SET_PDEATHSIG), so a
  `kill -9` of collect, train-ppo or evaluate leaves no worker writing files for a stage that is gone.
* `worker_pool`: a ProcessPoolExecutor whose workers do that and ignore SIGINT: Ctrl-C reaches the whole process
  group, and only the parent decides what happens (it records what finished, then stops the workers).
* `sigint_flag`: turns SIGINT into a flag the parent polls, instead of a KeyboardInterrupt raised at an arbitrary
  point, where it can be lost (raised inside a `__del__` or an atexit hook, Python prints and drops it).
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

_PR_SET_PDEATHSIG = 1  # from <linux/prctl.h>


def die_with_parent(parent_pid: int) -> None:
    """In a forked child: be killed when `parent_pid` exits (Linux; elsewhere a no-op). Safe to call in the parent
    itself (then it does nothing), so env constructors that may run in either can call it."""
    if os.getpid() == parent_pid or not sys.platform.startswith("linux"):
        return
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent_pid:  # the parent died before the request took effect
        os._exit(1)


def _pool_worker_init(parent_pid: int, ignore_sigint: bool) -> None:
    die_with_parent(parent_pid)
    if ignore_sigint:
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def worker_pool(workers: int, ignore_sigint: bool = True) -> ProcessPoolExecutor:
    """A fork-based pool whose workers die with this process and (by default) leave Ctrl-C to it: then the parent
    must stop them itself (`stop_pool`), as collect does under `sigint_flag`."""
    return ProcessPoolExecutor(
        max_workers=workers, mp_context=get_context("fork"), initializer=_pool_worker_init,
        initargs=(os.getpid(), ignore_sigint),
    )


def stop_pool(pool: ProcessPoolExecutor) -> None:
    """Kill the running workers now and drop the queued work (partial outputs are temp files, never final).

    The executor then fails every unfinished future with BrokenProcessPool; finished ones keep their results.
    (Cancelling futures first would race the executor's own cleanup, which then fails on a cancelled future.)"""
    procs = list((getattr(pool, "_processes", None) or {}).values())  # the executor has no public handle on them
    for proc in procs:
        proc.terminate()
    for proc in procs:
        proc.join(timeout=5)
    pool.shutdown(wait=True)


@contextlib.contextmanager
def sigint_flag() -> Iterator[Callable[[], bool]]:
    """Within the block, SIGINT sets a flag (read by calling the yielded function) instead of raising; the old
    handler is restored after. Outside the main thread (where handlers cannot be set) the flag stays False."""
    hit = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield hit.is_set
        return
    previous = signal.signal(signal.SIGINT, lambda *_: hit.set())
    try:
        yield hit.is_set
    finally:
        signal.signal(signal.SIGINT, previous)
