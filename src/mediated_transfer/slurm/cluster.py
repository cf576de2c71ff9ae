"""What the cluster allows and where submitted jobs are, read from sinfo and squeue.

Parsing is separate from calling, so it is tested on sample output without SLURM.
"""

from __future__ import annotations

import getpass
import re
import shutil
import subprocess
from dataclasses import dataclass


class ClusterError(RuntimeError):
    """A one-line reason the sweep cannot be submitted or waited for."""


@dataclass(frozen=True)
class Partition:
    name: str
    default: bool
    max_minutes: float  # inf: no limit
    memory_mb: int | None  # smallest node's memory; None: unknown
    cpus: int | None  # smallest node's CPUs; None: unknown


# sinfo -o format: partition, time limit, memory per node (MB), CPUs per node.
SINFO_FORMAT = "%P|%l|%m|%c"
# squeue -o format: job (array task) id, state, reason.
SQUEUE_FORMAT = "%i|%T|%r"


def parse_time_limit(text: str) -> float:
    """Minutes of a SLURM time limit: ``infinite``, ``M``, ``M:S``, ``H:M:S``, ``D-H[:M[:S]]``."""
    text = text.strip()
    if text in ("infinite", "UNLIMITED", "n/a", ""):
        return float("inf")
    days = 0
    if "-" in text:
        d, text = text.split("-", 1)
        days = int(d)
        parts = [int(p) for p in text.split(":")] + [0, 0]
        hours, minutes, seconds = parts[:3]
    else:
        parts = [int(p) for p in text.split(":")]
        if len(parts) == 1:
            hours, minutes, seconds = 0, parts[0], 0
        elif len(parts) == 2:
            hours, (minutes, seconds) = 0, parts
        else:
            hours, minutes, seconds = parts[:3]
    return days * 1440 + hours * 60 + minutes + seconds / 60


def _number(text: str) -> int | None:
    match = re.match(r"\d+", text.strip())
    return int(match.group()) if match else None


def parse_sinfo(text: str) -> list[Partition]:
    """Partitions from ``sinfo -h -o SINFO_FORMAT`` (one line per partition and node kind;
    the most restrictive kept)."""
    found: dict[str, Partition] = {}
    for line in text.splitlines():
        if not line.strip():
            continue
        name, limit, memory, cpus = line.split("|")[:4]
        default = name.endswith("*")
        name = name.rstrip("*")
        part = Partition(name, default, parse_time_limit(limit), _number(memory), _number(cpus))
        if name in found:
            old = found[name]
            part = Partition(name, default or old.default, min(part.max_minutes, old.max_minutes),
                             _min(part.memory_mb, old.memory_mb), _min(part.cpus, old.cpus))
        found[name] = part
    return list(found.values())


def _min(a: int | None, b: int | None) -> int | None:
    return b if a is None else a if b is None else min(a, b)


def check_request(partitions: list[Partition], partition: str | None, timeout_min: float,
                  mem_gb: float | None, cpus_per_task: int | None) -> Partition:
    """The partition the jobs go to; ClusterError (one line, naming the key) if SLURM would
    refuse them or leave them PENDING forever."""
    if partition:
        chosen = next((p for p in partitions if p.name == partition), None)
        if chosen is None:
            names = ", ".join(p.name for p in partitions) or "none"
            raise ClusterError(f"hydra.launcher.partition={partition}: no such partition; allowed: {names}")
    else:
        chosen = next((p for p in partitions if p.default), None)
        if chosen is None:
            raise ClusterError("hydra.launcher.partition is null but the cluster has no default "
                               f"partition; allowed: {', '.join(p.name for p in partitions)}")
    if timeout_min > chosen.max_minutes:
        raise ClusterError(
            f"hydra.launcher.timeout_min={timeout_min:g} is above partition {chosen.name}'s time limit "
            f"of {chosen.max_minutes:g} min (the jobs would stay PENDING forever): lower it, or choose "
            "another partition")
    if mem_gb is not None and chosen.memory_mb is not None and mem_gb * 1024 > chosen.memory_mb:
        raise ClusterError(
            f"hydra.launcher.mem_gb={mem_gb:g} is above the memory of partition {chosen.name}'s nodes "
            f"({chosen.memory_mb / 1024:.1f} GB): lower it")
    if cpus_per_task is not None and chosen.cpus is not None and cpus_per_task > chosen.cpus:
        raise ClusterError(
            f"hydra.launcher.cpus_per_task={cpus_per_task} is above the CPUs of partition "
            f"{chosen.name}'s nodes ({chosen.cpus}): lower it")
    return chosen


def parse_squeue(text: str) -> dict[str, tuple[str, str]]:
    """{job id: (state, reason)} from ``squeue -h -r -o SQUEUE_FORMAT``."""
    jobs = {}
    for line in text.splitlines():
        if line.count("|") >= 2:
            job, state, reason = line.split("|", 2)
            jobs[job.strip()] = (state.strip(), reason.strip())
    return jobs


def _slurm(*args: str) -> str:
    if shutil.which(args[0]) is None:
        raise ClusterError(f"{args[0]} not found: hydra/launcher=slurm runs on a SLURM login node "
                           "(SLURM's commands on PATH)")
    try:
        done = subprocess.run(list(args), capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        raise ClusterError(f"{args[0]} did not answer within 60 s (is slurmctld up?)") from None
    if done.returncode != 0:
        message = (done.stderr.strip() or done.stdout.strip() or f"exit code {done.returncode}").splitlines()[0]
        raise ClusterError(f"{args[0]} failed: {message}")
    return done.stdout


def partitions() -> list[Partition]:
    return parse_sinfo(_slurm("sinfo", "-h", "-o", SINFO_FORMAT))


def queue() -> dict[str, tuple[str, str]]:
    """This user's jobs in the queue (PENDING, RUNNING, ...), one entry per array task."""
    return parse_squeue(_slurm("squeue", "-h", "-r", "-u", getpass.getuser(), "-o", SQUEUE_FORMAT))


def cancel(job_ids: list[str]) -> None:
    if job_ids:
        subprocess.run(["scancel", *job_ids], capture_output=True, timeout=60)
