"""A launcher's worker notices that its launcher is gone; a process started from a shell does not
stop when that shell exits (nohup)."""

from __future__ import annotations

import itertools
import multiprocessing

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
