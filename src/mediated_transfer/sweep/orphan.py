"""Whether a worker process has lost the launcher that collects its work, and a worker that ends
when it has.

A parallel sweep's or tuning's worker whose launcher was killed (SIGKILL, an out-of-memory kill)
would compute on for hours with nobody to collect the result, and an idle one would wait for
work (joblib's loky workers: 300 s) holding ~0.5 GB and the pool's resource trackers. A sweep's
worker watches its launcher from a thread (``guard``): once it is gone, the run it computes is
interrupted as Ctrl-C would (its MLflow run ends KILLED, a rerun redoes it) and the process
exits; the resource trackers end with the last process that holds their pipe. A process started
from a shell is not a worker: it keeps going when that shell exits (nohup, a closed terminal,
`&` in a script).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator

POLL_S = 0.5
"""How often a worker's watch looks for its launcher."""
GRACE_S = 30.0
"""How long an interrupted run may take to end its MLflow run before the worker exits anyway."""


def launcher_watch() -> Callable[[], bool]:
    """A check, true once this process's launcher is gone. Only a process that a launcher's pool
    started (multiprocessing, joblib's loky) has one; in any other process it is never true."""
    if multiprocessing.parent_process() is None:
        return lambda: False
    launcher = os.getppid()
    # An orphan is re-parented (to init or a subreaper), so its parent's pid changes.
    return lambda: os.getppid() != launcher


class _Guard:
    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.working = 0
        self.gone = False
        self.thread: threading.Thread | None = None


_guard = _Guard()


@contextlib.contextmanager
def guard() -> Iterator[None]:
    """The ``with`` block is a job's work. In a pool's worker, a thread (started once) ends the
    process once its launcher is gone: at once when idle, else after interrupting the work and
    letting it unwind (so it ends its MLflow run), at most ``GRACE_S`` later."""
    orphaned = launcher_watch()
    with _guard.lock:
        if _guard.gone or orphaned():
            raise KeyboardInterrupt("the launching process is gone")
        _guard.working += 1
        if _guard.thread is None and multiprocessing.parent_process() is not None:
            _interruptible()
            _guard.thread = threading.Thread(target=_watch, args=(orphaned,), name="launcher-watch", daemon=True)
            _guard.thread.start()
    try:
        yield
    finally:
        with _guard.lock:
            _guard.working -= 1


def _interruptible() -> None:
    """SIGINT raises KeyboardInterrupt in this worker: a launcher started in the background
    (`nohup cmd &` in a script) passes SIGINT ignored to its pool, and the watch's interrupt
    would do nothing (the run would compute on until GRACE_S, its MLflow run left RUNNING)."""
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGINT) in (
            signal.SIG_IGN, signal.SIG_DFL):
        signal.signal(signal.SIGINT, signal.default_int_handler)


def _watch(orphaned: Callable[[], bool]) -> None:
    while not orphaned():
        time.sleep(POLL_S)
    with _guard.lock:
        _guard.gone = True  # no job starts any more (the pool may have handed this one more)
        working = _guard.working
    if working:
        # A real signal, not a flag: it also ends a wait in a system call (a locked store).
        signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)
        deadline = time.monotonic() + GRACE_S
        while _guard.working and time.monotonic() < deadline:
            time.sleep(0.05)
    os._exit(1)  # not sys.exit: the pool's machinery would wait for its dead launcher
