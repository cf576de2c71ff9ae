"""How the launchers hand lockstep groups to a process: which jobs of a sweep go together, and
one group's jobs run as Hydra jobs (each its folder, .hydra/ record and log) whose runs are
computed together (sweep.job.run_jobs).

Jobs go together when they differ only in their seed (one table cell of one configuration);
finished runs are left out of the groups (their jobs only skip), so a resumed sweep groups the
runs it still has to compute.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from hydra.core.hydra_config import HydraConfig
from hydra.core.utils import JobReturn, JobStatus, run_job
from omegaconf import DictConfig

from . import _with_seed, _without_seed


def group_size(cfg: DictConfig, cell_runs: int) -> int:
    """Runs per group for a cell with ``cell_runs`` runs to compute: ``lockstep.runs``, or when
    null 1 on the CPU (measured: grouping gains nothing there) and all of them on a GPU."""
    runs = cfg.lockstep.runs
    if runs is None:
        return 1 if str(cfg.lockstep.device) == "cpu" else max(1, cell_runs)
    return int(runs)


def lockstep_groups(job_overrides: Sequence[Sequence[str]], config_of: Callable[[list[str]], DictConfig],
                    finished: Callable[[DictConfig], bool]) -> list[list[int]]:
    """Indices into ``job_overrides``, grouped: unfinished jobs of one cell ``group_size`` at a
    time, in the order of their first job; every finished job alone. ``config_of`` composes a
    job's config (called once per cell), ``finished`` says whether a job's run is done."""
    cells: dict[tuple[str, ...], list[int]] = {}
    for i, overrides in enumerate(job_overrides):
        cells.setdefault(_without_seed(overrides), []).append(i)
    groups: list[list[int]] = []
    for indices in cells.values():
        base = config_of(list(job_overrides[indices[0]]))
        pending = []
        for i in indices:
            # Seeds change nothing else: the cell's config with this job's seed.
            if finished(_with_seed(base, job_overrides[i])):
                groups.append([i])
            else:
                pending.append(i)
        size = group_size(base, len(pending))
        groups += [pending[j:j + size] for j in range(0, len(pending), size)]
    return groups


def run_group(jobs: Sequence[tuple[DictConfig, Any]]) -> list[JobReturn]:
    """Run a group's jobs in this process: ``jobs`` are (sweep config, Hydra context) pairs as a
    launcher builds them for ``hydra.core.utils.run_job``. Each job is set up by Hydra (folder,
    .hydra/, logging); their runs are then computed together. A failure fails the group's
    unfinished jobs, each with the error."""
    from .job import run_jobs

    returns, prepared = [], []
    for sweep_config, hydra_context in jobs:
        HydraConfig.instance().set_config(sweep_config)
        ret = run_job(hydra_context=hydra_context, task_function=_job_of, config=sweep_config,
                      job_dir_key="hydra.sweep.dir", job_subdir_key="hydra.sweep.subdir")
        returns.append(ret)
        if ret.status == JobStatus.COMPLETED:
            prepared.append((len(returns) - 1, ret.return_value))
    try:
        summaries = run_jobs([job for _, job in prepared])
    except Exception as error:  # noqa: BLE001 - reported per job, as Hydra reports a job's error
        for i, _ in prepared:
            returns[i].status, returns[i].return_value = JobStatus.FAILED, error
        return returns
    for (i, _), summary in zip(prepared, summaries):
        returns[i].return_value = summary
    return returns


def _job_of(cfg: DictConfig) -> tuple:
    """The task function of a grouped job: what sweep.job.run_job needs, from Hydra's job context
    (the run itself is computed with its group)."""
    hydra_cfg = HydraConfig.get()
    return cfg, hydra_cfg.runtime.output_dir, hydra_cfg.sweep.dir, str(hydra_cfg.job.override_dirname)
