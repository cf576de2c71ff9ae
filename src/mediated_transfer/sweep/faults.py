"""Faults of what a command writes to, reported in one line: a full disk (a full quota, a file
over the size limit) and a damaged MLflow store.

A job that meets one (sweep/job.py) raises it as a ``Fault``, whose message is the command's
whole report: the run, the file, what to do. The entry point (app.py) prints it for a single
run or a sweep run in its own process; a pool's worker hands it back as the job's error, and
the launcher prints it once its other jobs have ended (nothing they compute is lost).
"""

from __future__ import annotations

import errno
import io
import logging
import os
import re
import sys
from collections.abc import Iterator
from pathlib import Path


class Fault(Exception):
    """A fault of the disk or the store a command writes to; the message (one line) is the whole
    report. ``file``: the file it could not write, if known."""

    def __init__(self, message: str, file: str | None = None):
        super().__init__(message)
        self.file = file

    def __reduce__(self):  # a worker hands it to its launcher
        return type(self), (str(self), self.file)

    def of(self, label: str) -> "Fault":
        """The same fault, naming the run it stopped (``regular_15 seed=3: ...``)."""
        return type(self)(f"{label}: {self}", self.file) if label else self


class DiskFull(Fault):
    """A file could not be written: its file system or quota is full, or the file is larger than
    the size limit."""


class StoreDamaged(Fault):
    """The SQLite MLflow store cannot be read."""


FULL = {errno.ENOSPC: "free space on {fs}", errno.EDQUOT: "free space in your quota on {fs}",
        errno.EFBIG: "raise the file size limit (ulimit -f) or put paths.root on another file system"}
"""What fills up, and what frees it."""
SQLITE_FULL = "database or disk is full"
"""SQLite's message when it cannot grow its file or journal."""
SQLITE_DAMAGED = ("database disk image is malformed", "file is not a database",
                  "file is encrypted or is not a database")
"""SQLite's messages for a file that is not (any more) a database it can read."""
AGAIN = "run the same command again: finished runs are kept"
_ATOMIC_TMP = re.compile(r"\.[a-z0-9_]{8}\.tmp$")  # atomic.py writes <name>.<mkstemp's 8>.tmp, then renames it


def causes(error: BaseException) -> Iterator[BaseException]:
    """``error`` and the errors it arose from (``raise ... from``, or raised while handling)."""
    seen: set[int] = set()
    current: BaseException | None = error
    while current is not None and id(current) not in seen:
        seen.add(id(current))
        yield current
        current = current.__cause__ or current.__context__


def disk_full(error: BaseException, store: str | os.PathLike | None = None,
              where: str | os.PathLike | None = None) -> DiskFull | None:
    """``error`` as the one line of a full disk, if it is one (or arose from one); else None.
    ``store``: the SQLite store being written, whose own errors name no file; ``where``: a folder
    on the file system, when no file is named."""
    for cause in causes(error):
        if isinstance(cause, OSError) and cause.errno in FULL:
            code, reason = cause.errno, cause.strerror or os.strerror(cause.errno)
            path = file = _written_file(cause) or _written_file(error)
            break
        if store is not None and SQLITE_FULL in str(cause):
            code, reason, path, file = errno.ENOSPC, SQLITE_FULL, str(store), f"the MLflow store {store}"
            break
    else:
        return None
    fs = _file_system(path or where or os.getcwd())
    return DiskFull(f"could not write{' ' + file if file else ''}: {reason} ({errno.errorcode[code]}); "
                    f"{FULL[code].format(fs=fs)}, then {AGAIN}", path)


def _written_file(error: BaseException) -> str | None:
    """The file a failed write was writing: the error's own (a copy's destination), else the one
    the innermost frame of its traceback was writing (an error of ``write`` or ``close`` names
    none): atomic.py's target, or an open file (Hydra's record, a log)."""
    if isinstance(error, OSError) and (error.filename2 or error.filename):
        return _ATOMIC_TMP.sub("", os.fsdecode(error.filename2 or error.filename))
    frames = []
    tb = error.__traceback__
    while tb is not None:
        frames.append(tb.tb_frame)
        tb = tb.tb_next
    for frame in reversed(frames):
        if frame.f_globals.get("__name__") == "mediated_transfer.atomic" and "path" in frame.f_locals:
            return str(frame.f_locals["path"])
        for value in frame.f_locals.values():
            if (isinstance(value, io.IOBase) and isinstance(getattr(value, "name", None), str)
                    and set(str(getattr(value, "mode", ""))) & set("wax+")):
                return str(Path(value.name).absolute())
    return None


def _file_system(path: str | os.PathLike) -> str:
    """The mount point of the file system that holds ``path`` (or would)."""
    p = Path(path).absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    while not os.path.ismount(p) and p != p.parent:
        p = p.parent
    return str(p)


def store_damaged(error: BaseException, store: str | os.PathLike | None) -> StoreDamaged | None:
    """``error`` as the one line of a damaged SQLite store ``store``, if it is one; else None."""
    if store is None:
        return None
    for cause in causes(error):
        found = next((m for m in SQLITE_DAMAGED if m in str(cause)), None)
        if found is not None:
            # Its journal goes with it: left behind, SQLite would replay it into the new store.
            files = [str(store)] + [f"{store}{s}" for s in ("-journal", "-wal", "-shm") if Path(f"{store}{s}").exists()]
            move = "; ".join(f"mv {f} {f}.damaged" for f in files)
            return StoreDamaged(f"the MLflow store {store} is damaged ({found}): move it aside ({move}); the "
                                "runs' results are kept in their folders, and running a command again logs its "
                                "finished runs into a new store (make reports adds the cells' summaries); "
                                "or run with tracking=none", str(store))
    return None


class RunLog(logging.FileHandler):
    """A job's log file (Hydra's ``mediated_transfer.log``: conf/config.yaml), quiet when its disk
    is full: logging would print a traceback for every line it could not write, and the job
    reports the full disk itself, in one line (the lines still reach the console)."""

    def handleError(self, record: logging.LogRecord) -> None:
        error = sys.exc_info()[1]
        if error is not None and disk_full(error) is not None:
            return
        super().handleError(record)
