"""One line for each way a SLURM job can fail, instead of submitit's multi-page tracebacks.

Each message says what happened, which setting to change (hydra.launcher.<key>) and where the
job's log is; the launcher prints one per failed job and ends the command with a summary.
"""

from __future__ import annotations

import re
from pathlib import Path

from hydra.core.utils import JobReturn, JobStatus

# Pending reasons SLURM never resolves by waiting: the request is above a limit.
HOPELESS_REASONS = {
    "PartitionTimeLimit": "timeout_min is above the partition's time limit: lower hydra.launcher.timeout_min",
    "QOSMaxWallDurationPerJobLimit": "timeout_min is above the QOS's time limit: lower hydra.launcher.timeout_min",
    "AssocMaxWallDurationPerJobLimit": "timeout_min is above the account's time limit: lower hydra.launcher.timeout_min",
    "PartitionNodeLimit": "the job asks for more nodes than the partition allows",
    "PartitionConfig": "the partition cannot run the job as asked (hydra.launcher.partition, cpus_per_task, mem_gb)",
    "BadConstraints": "no node meets the request: lower hydra.launcher.mem_gb or cpus_per_task",
    "InvalidAccount": "hydra.launcher.account is not valid on this cluster",
    "InvalidQOS": "hydra.launcher.qos is not valid for this account or partition",
}


def sbatch_error(text: str) -> str:
    """The line of sbatch's output that says why it refused the jobs."""
    lines = [ln.strip() for ln in str(text).splitlines() if ln.strip()]
    errors = [ln for ln in lines if "sbatch: error:" in ln]
    line = errors[-1] if errors else (lines[-1] if lines else "no output")
    line = line.split("sbatch: error:", 1)[-1].strip()
    hint = ""
    low = line.lower()
    if "memory" in low:
        hint = ": lower hydra.launcher.mem_gb"
    elif "partition" in low:
        hint = ": check hydra.launcher.partition (sinfo lists them)"
    elif "time limit" in low:
        hint = ": lower hydra.launcher.timeout_min"
    elif "account" in low:
        hint = ": check hydra.launcher.account"
    return f"sbatch refused the jobs: {line}{hint}"


def ended_without_result(job_id: str, runs: list[str], log: Path | None, timeout_min: float,
                         runs_per_job: int) -> str:
    """Why job ``job_id`` (carrying ``runs``) left the queue without a result, from its log."""
    text = _tail(log)
    what = ", ".join(runs[:3]) + (f" and {len(runs) - 3} more" if len(runs) > 3 else "")
    where = f"; log: {log}" if log is not None else ""
    if "DUE TO TIME LIMIT" in text:
        per = f" for {runs_per_job} runs" if runs_per_job > 1 else ""
        return (f"job {job_id} ({what}) hit its time limit (hydra.launcher.timeout_min={timeout_min:g}"
                f"{per}): raise timeout_min up to the partition's limit, or lower runs_per_job; a rerun "
                f"keeps the runs that finished{where}")
    if re.search(r"oom[-_ ]kill|out of memory|exceeded job memory limit", text, re.IGNORECASE):
        return f"job {job_id} ({what}) ran out of memory: raise hydra.launcher.mem_gb{where}"
    if "CANCELLED" in text:
        return f"job {job_id} ({what}) was cancelled{where}"
    last = _last_error(text)
    return f"job {job_id} ({what}) ended without a result{': ' + last if last else ''}{where}"


def reached_time_limit(ret: JobReturn) -> bool:
    """A run stopped by submitit's signal before the job's time limit (UncompletedJobError,
    "timed-out"), or not started after one."""
    error = ret._return_value if ret.status == JobStatus.FAILED else None
    return isinstance(error, TimeoutError) or (
        type(error).__name__ == "UncompletedJobError" and "timed-out" in str(error))


def run_failed(run: str, ret: JobReturn, log: Path | None, timeout_min: float, runs_per_job: int) -> str:
    """One line for a run that failed inside its job."""
    error = ret._return_value
    where = f"; log: {log}" if log is not None else ""
    if reached_time_limit(ret):
        what = "not started" if isinstance(error, TimeoutError) else "stopped"
        per = f" for {runs_per_job} runs" if runs_per_job > 1 else ""
        return (f"run {run} {what}: its job reached its time limit (hydra.launcher.timeout_min="
                f"{timeout_min:g}{per}; submitit stops runs signal_delay_s before it): raise timeout_min, "
                f"or lower runs_per_job; a rerun keeps the runs that finished{where}")
    first = str(error).strip().splitlines()[0] if str(error).strip() else ""
    return f"run {run} failed: {type(error).__name__}: {first}{where}"


def _tail(path: Path | None, size: int = 20000) -> str:
    if path is None or not path.is_file():
        return ""
    with path.open("rb") as f:
        f.seek(max(0, path.stat().st_size - size))
        return f.read().decode(errors="replace")


def _last_error(text: str) -> str:
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    for line in reversed(lines):
        if re.search(r"error|Error|Exception|Killed", line):
            return line[:200]
    return ""
