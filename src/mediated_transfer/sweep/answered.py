"""A sweep whose every run is finished and logged is answered without Hydra's launch.

Re-running a finished sweep is common (``make reproduce-tables`` after the tables exist, a
report's command run twice, a sweep resumed after its last run ended). Its jobs would each only
find the run and log it to MLflow, which has it already; Hydra's launch and MLflow's client cost
seconds of imports for that. So preflight, which has judged every run already, asks here
whether anything would change, and if nothing would, prints the jobs' own progress lines.

Nothing would change when every run is whole (reused or reported stale, as the job would),
no other process holds a run's folder, and the MLflow store already holds exactly one complete
run per run key, in an experiment with the runs view: then the job's ``log_run`` would create
and delete nothing. The store is read directly (SQLite, read-only) for that; a server store, a
store this module cannot read, or any doubt sends the command through Hydra as before, where
the jobs do what is missing. What the answer does not do: Hydra's rewrite of each run's
``.hydra/`` files and log and of the sweep's ``multirun.yaml``, which would record the same
command again.
"""

from __future__ import annotations

import contextlib
import json
import logging
import sqlite3
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from ..provenance.judge import Verdict
from . import progress
from .claim import claimed
from .identity import run_label, run_tags

log = logging.getLogger("mediated_transfer")

LOG_FORMAT = "[%(asctime)s][%(name)s][%(levelname)s] - %(message)s"
"""Hydra's default job log format: the answer's lines read as the jobs' would."""


@dataclass(frozen=True)
class Found:
    """One job of the command: its config, its run's spec and folder, its variant, its verdict."""

    cfg: DictConfig
    spec: object
    folder: Path
    variant: str
    verdict: Verdict


@contextlib.contextmanager
def answerable(command: DictConfig, jobs: Sequence[Found]) -> Iterator[bool]:
    """Whether nothing of the command is left to compute or log; while the ``with`` block runs,
    the jobs' folders are held (as the jobs would hold them), so none can change meanwhile."""
    if not jobs or "slurm" in str(OmegaConf.select(command, "hydra.launcher._target_", default="")).lower():
        yield False  # a SLURM launch has its own answer (jobs queued elsewhere, wait=false)
        return
    if not all(job.verdict.kept and job.verdict.damaged is None for job in jobs):
        yield False
        return
    with contextlib.ExitStack() as claims:
        # Another process computing or logging one of them: the job says which.
        yield all(claims.enter_context(claimed(job.folder)) for job in jobs) and _logged(jobs)


def answer(jobs: Sequence[Found]) -> None:
    """Each job's progress line, as the job would print it (on standard output, in Hydra's
    default format, unless logging is configured already)."""
    handler = None
    if not logging.getLogger().handlers:
        handler = logging.StreamHandler(sys.stdout)
        handler.setFormatter(logging.Formatter(LOG_FORMAT))
        log.addHandler(handler)
    level = log.level
    log.setLevel(logging.INFO)
    try:
        for job in jobs:
            log.info("%s", _line(job))
    finally:
        log.setLevel(level)
        if handler is not None:
            log.removeHandler(handler)


def _line(job: Found) -> str:
    cfg, verdict = job.cfg, job.verdict
    sweep_dir = Path(cfg.hydra.sweep.dir)
    run = job.folder.resolve().relative_to(sweep_dir.resolve()).as_posix()
    return progress.run_line(run_label(cfg, job.variant), verdict.result, "exists",
                             f"{cfg.name}/{cfg.scale.name}", sweep_dir, run, verdict.stale)


def _logged(jobs: Sequence[Found]) -> bool:
    """Whether the store already holds exactly one complete MLflow run of each job's run key
    (or tracking is off), read without MLflow; False when in doubt."""
    tracked = [job for job in jobs if job.cfg.tracking.enabled]
    if not tracked:
        return True
    uris = {str(job.cfg.tracking.uri) for job in tracked}
    experiments = {str(job.cfg.name) for job in tracked}
    if len(uris) != 1 or len(experiments) != 1 or not next(iter(uris)).startswith("sqlite:///"):
        return False
    store = Path(next(iter(uris)).removeprefix("sqlite:///"))
    if not store.is_file():
        return False
    keys = [run_tags(job.cfg, job.folder, job.spec, job.variant,
                     str(job.verdict.result.code.get("digest", "")))["run_key"] for job in tracked]
    try:
        with contextlib.closing(sqlite3.connect(f"{store.resolve().as_uri()}?mode=ro", uri=True,
                                                timeout=5)) as db:
            return _holds(db, next(iter(experiments)), keys)
    except sqlite3.Error:
        return False  # another schema, a damaged file: the jobs' MLflow client says what is wrong


def _holds(db: sqlite3.Connection, experiment: str, keys: Sequence[str]) -> bool:
    from .tracking import RUNS_VIEW, RUNS_VIEW_STATE, key_hash

    found = db.execute("SELECT experiment_id FROM experiments WHERE name = ? AND lifecycle_stage = 'active'",
                       (experiment,)).fetchall()
    if len(found) != 1:
        return False
    experiment_id = found[0][0]
    view = db.execute("SELECT value FROM experiment_tags WHERE experiment_id = ? AND key = ?",
                      (experiment_id, f"mlflow.sharedViewState.{RUNS_VIEW}")).fetchall()
    if view != [(json.dumps(RUNS_VIEW_STATE),)]:
        return False
    for key in keys:
        runs = db.execute(
            "SELECT r.status, EXISTS (SELECT 1 FROM tags f WHERE f.run_uuid = r.run_uuid AND f.key = 'failure') "
            "FROM runs r JOIN tags t ON t.run_uuid = r.run_uuid "
            "WHERE r.experiment_id = ? AND r.lifecycle_stage = 'active' AND t.key = 'run_key_hash' AND t.value = ?",
            (experiment_id, key_hash(key))).fetchall()
        # As tracking._existing counts a run complete: FINISHED, or FAILED with its reason.
        if len(runs) != 1 or not (runs[0][0] == "FINISHED" or (runs[0][0] == "FAILED" and runs[0][1])):
            return False
    return True
