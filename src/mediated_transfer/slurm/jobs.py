"""Which runs of a sweep need a SLURM job, and how they are packed into jobs.

A finished run would only start Python on a node to skip itself (sweep.job.run_job), so it is settled
in the launching process instead; the runs left are packed ``runs_per_job`` to a job, in sweep
order (the seeds of a cell are adjacent), because starting Python costs a job ~8 s.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from omegaconf import DictConfig

from ..config.compose import ConfigError
from ..provenance.judge import judge
from ..sweep import _with_seed, _without_seed


@dataclass(frozen=True)
class PlannedRun:
    """One job of Hydra's sweep: its overrides, its index in the sweep, its config and folder."""

    overrides: tuple[str, ...]
    index: int
    config: DictConfig
    folder: Path


def is_finished(folder: Path, rerun_stale: bool, place: tuple[str, int] | None = None) -> bool:
    """True when sweep.job.run_job would skip the run in ``folder``: a result is there, it is not
    damaged, it is the run of ``place`` (the folder's table cell and seed, when given), not
    another's moved or copied there, and it is not a stale one that ``rerun_stale`` asks to
    recompute (provenance/judge.py: its verdict is reuse or reported stale)."""
    return judge(folder, place=place, rerun_stale=rerun_stale).kept


def plan_runs(job_overrides: Sequence[Sequence[str]], initial_index: int,
              load: Callable[[list[str]], DictConfig]) -> list[PlannedRun]:
    """Every job's config and folder. ``load`` composes a job's config as Hydra does for the job
    (load_sweep_config); seeds do not change the rest, so it is called once per distinct rest."""
    composed: dict[tuple[str, ...], DictConfig] = {}
    runs = []
    for offset, overrides in enumerate(job_overrides):
        rest = _without_seed(overrides)
        if rest not in composed:
            composed[rest] = load(list(overrides))
        cfg = _with_seed(composed[rest], overrides)
        folder = Path(str(cfg.hydra.sweep.dir)) / str(cfg.hydra.sweep.subdir)
        runs.append(PlannedRun(tuple(overrides), initial_index + offset, cfg, folder))
    return runs


def place_of(cfg: DictConfig) -> tuple[str, int]:
    """The table cell and seed a job's folder is for."""
    return str(cfg.cell), int(cfg.seed)


def split_finished(runs: Sequence[PlannedRun]) -> tuple[list[PlannedRun], list[PlannedRun]]:
    """(finished, to compute), each in sweep order."""
    finished, pending = [], []
    for run in runs:
        finished_run = is_finished(run.folder, bool(run.config.rerun_stale), place_of(run.config))
        (finished if finished_run else pending).append(run)
    return finished, pending


def group_runs(runs: Sequence[PlannedRun], runs_per_job: int) -> list[list[PlannedRun]]:
    """Consecutive runs, ``runs_per_job`` to a job (the last job may carry fewer)."""
    if not isinstance(runs_per_job, int) or isinstance(runs_per_job, bool) or runs_per_job < 1:
        raise ConfigError(f"hydra.launcher.runs_per_job={runs_per_job!r}: must be an integer >= 1")
    return [list(runs[i:i + runs_per_job]) for i in range(0, len(runs), runs_per_job)]


def lockstep_groups_of(runs: Sequence[PlannedRun]) -> list[list[PlannedRun]] | None:
    """The runs grouped for lockstep, one group per job (sweep.groups.lockstep_groups);
    None when no group has more than one run (then runs_per_job packs them)."""
    from ..sweep.groups import lockstep_groups

    configs = {run.overrides: run.config for run in runs}
    groups = lockstep_groups([run.overrides for run in runs], lambda o: configs[tuple(o)], lambda cfg: False)
    if all(len(group) == 1 for group in groups):
        return None
    return [[runs[i] for i in group] for group in groups]
