"""One process at a time per run folder: a claim held while a run is computed or logged.

Two launches of the same sweep (or two overlapping sweeps) reach the same run folders. Whoever
claims a folder first computes and logs its run; the other finds the claim held and skips the
run at once, so no run is computed twice and no MLflow run is deleted while another process
is still logging it. The claim is an advisory lock (``flock``) on a file in the folder: the
kernel releases it when its holder ends, however it ends (even SIGKILL), so a claim never
outlives a dead process.

While it holds a claim, a job records in the claim file what it computes there (its process,
host, sweep and the run's comparable config; ``holder``), and empties the file before letting
go. The other process reads it: a claim for the same run is the supported case (two launches of
one sweep) and is skipped quietly; a claim for another configuration is two sweeps of different
configurations sharing a folder, which the job names instead of skipping (sweep/job.py).

Lock files (a claim, the SQLite store's lock) are created with the user's usual mode (umask),
as results are: under umask 002 a collaborator of the same group locks them too.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import socket
import time
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

CLAIM_FILE = ".claim"
HOLDER_WAIT_S = 0.5
"""How long ``holder`` waits for a claim's holder to record itself (it does right after locking)."""


@contextlib.contextmanager
def claimed(folder: str | os.PathLike, record: Mapping[str, Any] | None = None) -> Iterator[bool]:
    """Hold ``folder``'s claim for the ``with`` block; yields False (holding nothing) when
    another process holds it. ``record`` (JSON values): what the holder computes there, written
    into the claim file, with its pid and host, for as long as the claim is held."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    fd = open_lock_file(folder / CLAIM_FILE)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            yield False
            return
        written = record is not None and _write(fd, record)
        try:
            yield True
        finally:
            if written:  # a free claim records nobody
                with contextlib.suppress(OSError):
                    os.ftruncate(fd, 0)
            fcntl.flock(fd, fcntl.LOCK_UN)
    finally:
        os.close(fd)


def holder(folder: str | os.PathLike, wait_s: float = HOLDER_WAIT_S) -> dict[str, Any] | None:
    """What the process holding ``folder``'s claim recorded (``pid``, ``host`` and its ``record``);
    None when it recorded nothing within ``wait_s`` (code from before claims were recorded, a
    claim file it could not write, or the claim is free by now)."""
    deadline = time.monotonic() + wait_s
    while True:
        found = _read(Path(folder) / CLAIM_FILE)
        if found is not None or time.monotonic() >= deadline:
            return found
        time.sleep(0.02)


def _write(fd: int, record: Mapping[str, Any]) -> bool:
    text = json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "record": dict(record)},
                      sort_keys=True, default=str)
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, text.encode(), 0)
    except OSError:  # e.g. another user's claim file, opened read-only: the claim holds, unrecorded
        return False
    return True


def _read(path: Path) -> dict[str, Any] | None:
    try:
        found = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):  # empty, or being written
        return None
    if not isinstance(found, dict) or not isinstance(found.get("record"), dict):
        return None
    if found.get("host") == socket.gethostname() and not _alive(found.get("pid")):
        return None  # left by a holder killed before it could empty it: the new holder rewrites it
    return found


def _alive(pid: Any) -> bool:
    if not isinstance(pid, int) or pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def open_lock_file(path: str | os.PathLike) -> int:
    """A descriptor to ``flock`` ``path`` with, creating it as 0666 less the umask. A lock file
    another user made without group write access is opened read-only: flock needs no write
    access (NFS's emulation does; there, the umask above is what makes it work)."""
    try:
        return os.open(path, os.O_CREAT | os.O_RDWR, 0o666)
    except PermissionError:
        return os.open(path, os.O_RDONLY)
