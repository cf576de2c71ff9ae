"""One process at a time per run folder: a claim held while a run is computed or logged.

Two launches of the same sweep (or two overlapping sweeps) reach the same run folders. Whoever
claims a folder first computes and logs its run; the other finds the claim held and skips the
run at once, so no run is computed twice and no MLflow run is deleted while another process
is still logging it. The claim is an advisory lock (``flock``) on a file in the folder: the
kernel releases it when its holder ends, however it ends (even SIGKILL), so a claim never
outlives a dead process.

Lock files (a claim, the SQLite store's lock) are created with the user's usual mode (umask),
as results are: under umask 002 a collaborator of the same group locks them too.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
from collections.abc import Iterator
from pathlib import Path

CLAIM_FILE = ".claim"


@contextlib.contextmanager
def claimed(folder: str | os.PathLike) -> Iterator[bool]:
    """Hold ``folder``'s claim for the ``with`` block; yields False (holding nothing) when
    another process holds it."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    fd = open_lock_file(folder / CLAIM_FILE)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            yield False
            return
        try:
            yield True
        finally:
            fcntl.flock(fd, fcntl.LOCK_UN)
    finally:
        os.close(fd)


def open_lock_file(path: str | os.PathLike) -> int:
    """A descriptor to ``flock`` ``path`` with, creating it as 0666 less the umask. A lock file
    another user made without group write access is opened read-only: flock needs no write
    access (NFS's emulation does; there, the umask above is what makes it work)."""
    try:
        return os.open(path, os.O_CREAT | os.O_RDWR, 0o666)
    except PermissionError:
        return os.open(path, os.O_RDONLY)
