"""Whether a worker process has lost the launcher that collects its work.

A parallel sweep's or tuning's worker whose launcher was killed (SIGKILL, an out-of-memory kill)
would compute on for hours with nobody to collect the result; it stops at its next evaluation
point instead, and a rerun redoes it. A process started from a shell is not a worker: it keeps
going when that shell exits (nohup, a closed terminal, `&` in a script).
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable


def launcher_watch() -> Callable[[], bool]:
    """A check, true once this process's launcher is gone. Only a process that a launcher's pool
    started (multiprocessing, joblib's loky) has one; in any other process it is never true."""
    if multiprocessing.parent_process() is None:
        return lambda: False
    launcher = os.getppid()
    # An orphan is re-parented (to init or a subreaper), so its parent's pid changes.
    return lambda: os.getppid() != launcher
