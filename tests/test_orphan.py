"""A launcher's worker notices that its launcher is gone, and exits within seconds; a process
started from a shell does not stop when that shell exits (nohup)."""

from __future__ import annotations

import contextlib
import itertools
import multiprocessing
import os
import signal
import subprocess
import sys
import time

import pytest

from mediated_transfer.sweep import orphan


def _reparented(monkeypatch) -> None:
    """getppid: the launcher at the start, init ever after."""
    parents = itertools.chain([4242], itertools.repeat(1))
    monkeypatch.setattr(orphan.os, "getppid", lambda: next(parents))


def orphaned_pool_worker(monkeypatch) -> None:
    """This process as a launcher's pool worker whose launcher dies after its first check."""
    monkeypatch.setattr(orphan.multiprocessing, "parent_process", lambda: object())
    _reparented(monkeypatch)


def test_a_pool_worker_is_orphaned_once_its_launcher_is_gone(monkeypatch):
    orphaned_pool_worker(monkeypatch)
    orphaned = orphan.launcher_watch()
    assert orphaned()


def test_a_pool_worker_with_its_launcher_is_not_orphaned():
    context = multiprocessing.get_context("spawn")
    with context.Pool(1) as pool:
        assert pool.apply(_watch_in_worker) == (True, False)


def _watch_in_worker() -> tuple[bool, bool]:
    return multiprocessing.parent_process() is not None, orphan.launcher_watch()()


def test_a_process_started_from_a_shell_is_never_orphaned(monkeypatch):
    """The main process (no pool started it): its shell exiting re-parents it, and it goes on."""
    assert multiprocessing.parent_process() is None
    _reparented(monkeypatch)
    orphaned = orphan.launcher_watch()
    assert not orphaned()


_POOL_OF_ONE = """
import multiprocessing, os, sys, time
from mediated_transfer.sweep.orphan import guard

marker, busy = sys.argv[1], sys.argv[2] == "busy"

def job():
    with guard():
        open(marker + ".started", "w").close()
        try:
            while busy:
                time.sleep(0.05)
        except KeyboardInterrupt:
            open(marker + ".interrupted", "w").close()
            raise

if __name__ == "__main__":
    pool = multiprocessing.get_context("fork").Pool(1)
    pool.apply_async(job)
    print(pool._pool[0].pid, flush=True)
    time.sleep(600)
"""


def _alive(pid: int) -> bool:
    try:
        return open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.skipif(not os.path.exists("/proc/self/stat"), reason="reads processes from /proc (Linux)")
@pytest.mark.parametrize("busy", ["busy", "idle", "busy-in-background"])
def test_a_pool_worker_exits_within_seconds_of_its_launchers_sigkill(tmp_path, busy):
    """The launcher SIGKILLed: its pool's worker interrupts the job it runs (as Ctrl-C would, so
    the run ends its MLflow run) and exits; an idle one exits at once, instead of waiting for
    work that never comes (loky: 300 s, multiprocessing's pool: forever). In the background
    (`nohup make ... &` in a script: SIGINT ignored, inherited by the pool) the same."""
    marker = str(tmp_path / "job")
    background = busy.endswith("-in-background")
    busy = busy.removesuffix("-in-background")
    launcher = subprocess.Popen([sys.executable, "-c", _POOL_OF_ONE, marker, busy], stdout=subprocess.PIPE, text=True,
                                preexec_fn=_ignore_sigint if background else None)
    worker = int(launcher.stdout.readline())
    try:
        deadline = time.time() + 60
        while not os.path.exists(marker + ".started") and time.time() < deadline:
            time.sleep(0.05)
        time.sleep(0.5)  # an idle job has returned
        launcher.kill()
        launcher.wait()
        deadline = time.time() + 20
        while _alive(worker) and time.time() < deadline:
            time.sleep(0.1)
        assert not _alive(worker), "the worker outlived its launcher by 20 s"
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.kill(worker, signal.SIGKILL)
    assert os.path.exists(marker + ".interrupted") == (busy == "busy")
