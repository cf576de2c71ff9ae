"""Wait for a sweep's SLURM jobs in the launching terminal: progress lines, one-line failures.

submitit's own wait asks sacct, which many clusters (and a single-node SLURM without a
database) do not have; then a job killed at its time limit is waited for forever. This loop
needs only the result files and squeue: a job that left the queue without a result failed,
and its log says why (errors.ended_without_result).
"""

from __future__ import annotations

import logging
import time
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hydra.core.utils import JobReturn, JobStatus

from ..sweep import progress
from . import cluster, errors

log = logging.getLogger("mediated_transfer")

# A result file may show up on a shared file system a little after its job left the queue.
GRACE_S = 15.0
TICK_S = 2.0


@dataclass
class Submitted:
    """One SLURM job (a submitit Job) and the run folders (below the sweep folder) it carries."""

    job: Any
    runs: list[str]


@dataclass
class Outcome:
    returns: list[JobReturn] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)


def wait(jobs: list[Submitted], sweep_dir: Path, sweep_name: str, every_s: float, timeout_min: float,
         runs_per_job: int, queue: Callable[[], Mapping[str, tuple[str, str]]] = cluster.queue,
         cancel: Callable[[list[str]], None] = cluster.cancel,
         sleep: Callable[[float], None] = time.sleep, clock: Callable[[], float] = time.monotonic) -> Outcome:
    """Wait until every job has a result or has left the queue; a progress line whenever the
    counts change (queue checked every ``every_s``). ClusterError if a job can never start."""
    outcome = Outcome()
    waiting = {s.job.job_id: s for s in jobs}
    first_run = next((r for s in jobs for r in s.runs), "")
    gone_since: dict[str, float] = {}
    last_check, last_line = -float("inf"), ""
    while waiting:
        for job_id, sub in list(waiting.items()):
            if sub.job.paths.result_pickle.exists():
                del waiting[job_id]
                _collect(sub, outcome, timeout_min, runs_per_job)
        if not waiting:
            break
        now = clock()
        if now - last_check >= every_s:
            last_check = now
            queued = queue()
            for job_id in list(waiting):
                if job_id in queued:
                    gone_since.pop(job_id, None)
                elif now - gone_since.setdefault(job_id, now) >= GRACE_S and \
                        not waiting[job_id].job.paths.result_pickle.exists():
                    sub = waiting.pop(job_id)
                    outcome.errors.append(errors.ended_without_result(
                        job_id, sub.runs, _log(sub.job), timeout_min, runs_per_job))
            _refuse_hopeless(waiting, queued, cancel)
            line = status_line(sweep_dir, sweep_name, first_run,
                               {j: queued[j] for j in waiting if j in queued})
            if line != last_line:
                log.info("%s", line)
                last_line = line
        sleep(TICK_S)
    log.info("%s", status_line(sweep_dir, sweep_name, first_run, {}).split(" SLURM jobs:")[0] + " all jobs done")
    return outcome


def status_line(sweep_dir: Path, sweep_name: str, run: str, queued: Mapping[str, tuple[str, str]]) -> str:
    """``[table2_rbf/paper 37/220, ~12m left] SLURM: 4 running, 10 pending (Priority)``."""
    count = progress.sweep_progress(sweep_dir, run)
    head = sweep_name
    if count is not None:
        finished, total, left = count
        head += f" {finished}/{total}" + ("" if left is None else f", ~{progress.duration(left)} left")
    states = Counter(state for state, _ in queued.values())
    reasons = Counter(reason for state, reason in queued.values() if state == "PENDING")
    parts = [f"{states.pop('RUNNING', 0)} running"]
    if "PENDING" in states:
        # "None": just submitted, the scheduler has not looked at it yet.
        why = ", ".join(r for r, _ in reasons.most_common(2) if r != "None")
        parts.append(f"{states.pop('PENDING')} pending" + (f" ({why})" if why else ""))
    parts += [f"{n} {state.lower()}" for state, n in sorted(states.items())]
    return f"[{head}] SLURM jobs: {', '.join(parts)}"


def _refuse_hopeless(waiting: Mapping[str, Submitted], queued: Mapping[str, tuple[str, str]],
                     cancel: Callable[[list[str]], None]) -> None:
    for job_id in waiting:
        state, reason = queued.get(job_id, ("", ""))
        if state == "PENDING" and reason in errors.HOPELESS_REASONS:
            cancel(list(waiting))
            raise cluster.ClusterError(f"job {job_id} can never start ({reason}): "
                                       f"{errors.HOPELESS_REASONS[reason]}; the sweep's jobs were cancelled")


def _collect(sub: Submitted, outcome: Outcome, timeout_min: float, runs_per_job: int) -> None:
    try:
        returns = sub.job.results()[0]
    except Exception as error:  # noqa: BLE001 - the job itself failed: its one line
        outcome.errors.append(errors.ended_without_result(sub.job.job_id, sub.runs, _log(sub.job),
                                                          timeout_min, runs_per_job)
                              if not str(error).strip() else
                              f"job {sub.job.job_id} failed: {errors._last_error(str(error)) or type(error).__name__}"
                              f"; log: {_log(sub.job)}")
        return
    for run, ret in returns:  # the launcher's run_group: (run folder, JobReturn) per run
        if ret.status == JobStatus.FAILED:
            outcome.errors.append(errors.run_failed(run, ret, _log(sub.job), timeout_min, runs_per_job))
        else:
            outcome.returns.append(ret)


def _log(job: Any) -> Path | None:
    try:
        return Path(job.paths.stderr)
    except Exception:  # noqa: BLE001 - a path only for the message
        return None
