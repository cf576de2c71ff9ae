"""A command stopped before its end (Ctrl-C, SIGTERM, a worker that died): no MLflow run left
RUNNING, and one line instead of a traceback.

A parallel sweep's pool kills its workers when the launcher is interrupted or one of them dies
(joblib: SIGKILL), so a run a worker was computing or logging cannot end its own MLflow run. The
launching process ends them before it exits (``settle``): each run of the command that nobody
computes any more (its claim is free) and whose MLflow run is still RUNNING ends KILLED, or,
when its result was written, FINISHED with the result logged in full.
"""

from __future__ import annotations

import contextlib
import re
import signal
import threading
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from ..results import RunResult
from . import tracking
from .claim import claimed

CLAIM_WAIT_S = 10.0
"""How long ``settle`` waits for a dead worker's claim to be released (the kernel does it as the
process ends)."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C's KeyboardInterrupt, raised for another signal (SIGTERM); ``signum`` names it."""

    def __init__(self, signum: int):
        super().__init__(f"signal {signum}")
        self.signum = signum


class WorkerLost(SystemExit):
    """A pool's worker process died (killed, out of memory); the message says how."""


@contextlib.contextmanager
def sigterm_interrupts() -> Iterator[None]:
    """SIGTERM (a scheduler's kill or time limit, ``kill``) as Ctrl-C for the ``with`` block, so
    what it stops ends cleanly (the default would end the process on the spot). Only the main
    thread can set it; elsewhere the block runs unchanged."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise Interrupted(signum)

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@dataclass(frozen=True)
class PlannedRun:
    """A run of a command: its folder, its MLflow experiment and store (None: not tracked, or
    computed elsewhere, by a SLURM job that outlives its launcher)."""

    folder: Path
    where: str
    """The folder as its MLflow run key begins (sweep.identity.run_where)."""
    experiment: str
    tracking: tracking.TrackingSettings | None


def exit_line(runs: Sequence[PlannedRun], error: BaseException) -> tuple[str, int]:
    """The line a stopped command ends with, and its exit status (128 + the signal)."""
    if isinstance(error, WorkerLost):
        what, status = str(error.code), 1
    else:
        signum = getattr(error, "signum", signal.SIGINT)
        what, status = f"interrupted ({signal.Signals(signum).name})", 128 + signum
    finished = sum(RunResult.exists(run.folder) for run in runs)
    counts = f": {finished} of {len(runs)} runs finished, {len(runs) - finished} left" if runs else ""
    return f"{what}{counts}; run the same command to resume (finished runs are kept)", status


def worker_lost_line(error: BaseException) -> str:
    """joblib's TerminatedWorkerError (a paragraph) as one line: how the worker ended."""
    codes = re.search(r"exit codes of the workers are (\{[^}]*\})", str(error))
    return f"a worker process died ({codes.group(1) if codes else type(error).__name__})"


def settle(runs: Sequence[PlannedRun]) -> int:
    """End the MLflow runs of ``runs`` left RUNNING by processes that are gone; returns how many."""
    ended = 0
    for (settings, experiment), group in _by_store(runs).items():
        with tracking._impatient():  # a server that is gone: fail in seconds, not retry for minutes
            ended += _settle_store(settings, experiment, group)
    return ended


def _settle_store(settings: tracking.TrackingSettings, experiment: str, group: list[PlannedRun]) -> int:
    client = settings.client()
    found = client.get_experiment_by_name(experiment)
    if found is None:
        return 0
    running: dict[str, list] = {}
    for run in tracking.running_runs(client, found.experiment_id):
        running.setdefault(run.data.tags.get("run_key", "").rsplit("@", 1)[0], []).append(run)
    ended = 0
    for planned in group:
        if running.get(planned.where) and _free(planned.folder):
            for run in running[planned.where]:
                _end(settings, run, planned.folder)
                ended += 1
    return ended


def _by_store(runs: Sequence[PlannedRun]) -> dict[tuple, list[PlannedRun]]:
    groups: dict[tuple, list[PlannedRun]] = {}
    for run in runs:
        if run.tracking is not None:
            groups.setdefault((run.tracking, run.experiment), []).append(run)
    return groups


def _free(folder: Path) -> bool:
    """Whether nobody holds the run's claim (within ``CLAIM_WAIT_S``): another launch may be
    computing it, and its live MLflow run is not ours to end."""
    deadline = time.monotonic() + CLAIM_WAIT_S
    while True:
        with claimed(folder) as mine:
            if mine:
                return True
        if time.monotonic() > deadline:
            return False
        time.sleep(0.2)


def _end(settings: tracking.TrackingSettings, run, folder: Path) -> None:
    live = tracking.LiveRun.resume(settings, run.info.run_id)
    result = _written(folder, since_ms=run.info.start_time)
    if result is not None:  # computed, stopped while being logged: logged in full, as its worker would have
        live.finish(result, tracking.run_artifacts(folder))
    else:
        live.end("KILLED")


def _written(folder: Path, since_ms: int) -> RunResult | None:
    """The result this run wrote (one older than its MLflow run is another's), if readable."""
    try:
        if (folder / "result.json").stat().st_mtime * 1000 < since_ms:
            return None
        return RunResult.read(folder)
    except (OSError, ValueError, KeyError, TypeError):
        return None
