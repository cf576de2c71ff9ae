"""Setting a damaged run aside: its files renamed in place, never deleted.

A sweep that finds a damaged run (check.py) renames its files to ``<name>.damaged-<time>`` and
computes the run again; the damaged files stay beside the new ones for whoever wants to know
what happened. Files are renamed, not the folder: a run's folder may hold its variants' folders.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from . import CURVE_FILE, LEARNER_FILES, RESULT_FILE

SUFFIX = ".damaged-"


def run_files() -> tuple[str, ...]:
    """What a run leaves in its folder: its record, its curve, its saved learner."""
    return (RESULT_FILE, CURVE_FILE, *LEARNER_FILES)


def set_aside(folder: str | Path) -> list[Path]:
    """Rename the run's files in ``folder`` with the suffix ``.damaged-<local time>`` (and ``-<n>``
    when that is taken); return their new paths. result.json goes first: the run stops being
    finished before anything else moves."""
    folder = Path(folder)
    names = [n for n in run_files() if os.path.lexists(folder / n)]
    stamp, n = time.strftime("%Y%m%dT%H%M%S"), 1
    suffix = f"{SUFFIX}{stamp}"
    while any(os.path.lexists(folder / (name + suffix)) for name in names):
        n += 1
        suffix = f"{SUFFIX}{stamp}-{n}"
    moved = []
    for name in names:
        target = folder / (name + suffix)
        os.rename(folder / name, target)
        moved.append(target)
    return moved
