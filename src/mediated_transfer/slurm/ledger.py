"""The sweep folder's record of the SLURM jobs its runs were submitted in.

A launcher that stops (logout, Ctrl-C) leaves its jobs queued or running. Run again, it finds
each unfinished run's job here and, while SLURM still lists that job, waits for it instead of
submitting the run a second time (two jobs writing one folder).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from pathlib import Path

from ..atomic import atomic_write_text

LEDGER_FILE = ".slurm_jobs.json"


class Ledger:
    def __init__(self, sweep_dir: Path):
        self.path = Path(sweep_dir) / LEDGER_FILE

    def read(self) -> dict[str, dict[str, str]]:
        """{run folder below the sweep folder: {"job": SLURM job id, "folder": submitit folder}}."""
        try:
            return json.loads(self.path.read_text())
        except (OSError, ValueError):
            return {}

    def live(self, runs: Iterable[str], queued: Mapping[str, object]) -> dict[str, dict[str, str]]:
        """The entries of ``runs`` whose job SLURM still lists (``queued``: squeue's jobs)."""
        entries = self.read()
        return {run: entries[run] for run in runs if run in entries and entries[run]["job"] in queued}

    def record(self, submitted: Mapping[str, dict[str, str]]) -> None:
        entries = self.read()
        entries.update(submitted)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(self.path, json.dumps(entries, indent=1, sort_keys=True) + "\n")
