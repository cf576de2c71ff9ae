"""``hydra/launcher=parallel`` (the default): Hydra's joblib launcher, one worker process per
core, which hands a cell's seeds to one worker as a lockstep group when ``lockstep.runs`` (or a
GPU device) asks for groups (mediated_transfer.sweep.groups). Without groups it is Hydra's
joblib launcher, except that a worker that dies ends the sweep in one line, and so does a full
disk or a damaged MLflow store (mediated_transfer.sweep.faults), once the other jobs have ended.
"""

# No `from __future__ import annotations`: Hydra's plugin scan executes this module outside
# sys.modules, where dataclasses cannot resolve string annotations.
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Sequence

from hydra.core.config_store import ConfigStore
from hydra.core.singleton import Singleton
from hydra.core.utils import JobReturn, JobStatus, configure_log, filter_overrides, setup_globals
from hydra_plugins.hydra_joblib_launcher._core import process_joblib_cfg
from hydra_plugins.hydra_joblib_launcher.config import JobLibLauncherConf
from hydra_plugins.hydra_joblib_launcher.joblib_launcher import JoblibLauncher
from omegaconf import DictConfig, open_dict

log = logging.getLogger("mediated_transfer")


@dataclass
class MediatedJoblibConf(JobLibLauncherConf):
    _target_: str = "hydra_plugins.mediated_transfer_launcher.local_launcher.MediatedJoblibLauncher"


ConfigStore.instance().store(group="hydra/launcher", name="mediated_joblib", node=MediatedJoblibConf(),
                             provider="mediated_transfer")


def _execute_group(indices: List[int], overrides: List[List[str]], hydra_context: Any, config: DictConfig,
                   singleton_state: Dict[Any, Any]) -> List[JobReturn]:
    """In a worker: the group's jobs, configured as Hydra's joblib launcher configures a job."""
    from mediated_transfer.sweep.groups import run_group

    setup_globals()
    Singleton.set_state(singleton_state)
    jobs = []
    for idx, job_overrides in zip(indices, overrides):
        sweep_config = hydra_context.config_loader.load_sweep_config(config, list(job_overrides))
        with open_dict(sweep_config):
            sweep_config.hydra.job.id = f"{sweep_config.hydra.job.name}_{idx}"
            sweep_config.hydra.job.num = idx
        jobs.append((sweep_config, hydra_context))
    try:
        return run_group(jobs)
    except Exception as error:  # noqa: BLE001 - Hydra's record of a job (.hydra/) could not be written
        return _faulted(error, overrides, [c for c, _ in jobs])


def _execute_job(idx: int, overrides: List[str], hydra_context: Any, config: DictConfig, task_function: Any,
                 singleton_state: Dict[Any, Any]) -> JobReturn:
    """In a worker: one job, as Hydra's joblib launcher runs it."""
    from hydra_plugins.hydra_joblib_launcher._core import execute_job

    try:
        return execute_job(idx, overrides, hydra_context, config, task_function, singleton_state)
    except Exception as error:  # noqa: BLE001 - Hydra's record of the job (.hydra/) could not be written
        return _faulted(error, [overrides], [hydra_context.config_loader.load_sweep_config(config, list(overrides))])[0]


def _faulted(error: Exception, overrides: List[List[str]], configs: List[DictConfig]) -> List[JobReturn]:
    """A full disk or a damaged store met before the jobs' own code ran (Hydra writing their
    .hydra/ record) as each job's error, naming the run and the file; any other error as
    before: raised, and the pool stops."""
    from mediated_transfer.sweep.job import job_fault

    jobs = [(c, Path(str(c.hydra.sweep.dir)) / str(c.hydra.sweep.subdir), None, str(c.hydra.job.override_dirname))
            for c in configs]
    fault = job_fault(error, jobs)
    if fault is None:
        raise error
    return [JobReturn(overrides=list(o), status=JobStatus.FAILED, _return_value=fault) for o in overrides]


class MediatedJoblibLauncher(JoblibLauncher):
    def launch(self, job_overrides: Sequence[Sequence[str]], initial_job_idx: int) -> Sequence[JobReturn]:
        from joblib.externals.loky.process_executor import BrokenProcessPool

        from mediated_transfer.sweep.interrupted import WorkerLost, worker_lost_line

        try:
            returns = self._launch(job_overrides, initial_job_idx)
        except BrokenProcessPool as error:
            # A worker died (killed, out of memory): one line, not joblib's paragraph and
            # traceback; the entry point ends the MLflow runs the pool's workers left RUNNING.
            raise WorkerLost(worker_lost_line(error)) from None
        _stop_on_fault(returns)
        return returns

    def _launch(self, job_overrides: Sequence[Sequence[str]], initial_job_idx: int) -> Sequence[JobReturn]:
        from joblib import Parallel, delayed

        from mediated_transfer.sweep.groups import lockstep_groups
        from mediated_transfer.slurm.jobs import is_finished, place_of

        assert self.config is not None and self.hydra_context is not None
        groups = lockstep_groups(
            job_overrides, lambda o: self.hydra_context.config_loader.load_sweep_config(self.config, o),
            lambda cfg: is_finished(Path(str(cfg.hydra.sweep.dir)) / str(cfg.hydra.sweep.subdir),
                                    bool(cfg.rerun_stale), place_of(cfg)))
        setup_globals()
        configure_log(self.config.hydra.hydra_logging, self.config.hydra.verbose)
        sweep_dir = Path(str(self.config.hydra.sweep.dir))
        sweep_dir.mkdir(parents=True, exist_ok=True)
        params = dict(self.joblib)
        params["backend"] = "loky"  # as Hydra's joblib launcher: threads are incompatible with Hydra
        process_joblib_cfg(params)
        if len(groups) == 1:
            # One job (or group): a pool would start a worker process for it, which imports
            # everything and composes the config again (a skip of a finished run: most of its
            # time); joblib runs a pool of one here, as Hydra's basic launcher would.
            params["n_jobs"] = 1
        state = Singleton.get_state()
        if all(len(g) == 1 for g in groups):  # Hydra's joblib launcher, its lines included
            log.info("Joblib.Parallel(%s) is launching %d jobs", ",".join(f"{k}={v}" for k, v in params.items()),
                     len(job_overrides))
            log.info("Launching jobs, sweep output dir : %s", sweep_dir)
            for idx, overrides in enumerate(job_overrides):
                log.info("\t#%d : %s", idx, " ".join(filter_overrides(overrides)))
            return Parallel(**params)(
                delayed(_execute_job)(initial_job_idx + idx, list(overrides), self.hydra_context, self.config,
                                      self.task_function, state)
                for idx, overrides in enumerate(job_overrides))
        log.info("%d jobs in %d lockstep groups (largest %d) on %s workers", len(job_overrides), len(groups),
                 max(len(g) for g in groups), params.get("n_jobs"))
        done = Parallel(**params)(
            delayed(_execute_group)([initial_job_idx + i for i in g], [list(job_overrides[i]) for i in g],
                                    self.hydra_context, self.config, state)
            for g in groups)
        by_index = {i: ret for g, rets in zip(groups, done) for i, ret in zip(g, rets)}
        return [by_index[i] for i in range(len(job_overrides))]


def _stop_on_fault(returns: Sequence[JobReturn]) -> None:
    """A job stopped by a full disk or a damaged MLflow store ends the sweep in its one line
    (the entry point ends the MLflow runs left RUNNING), not in Hydra's traceback."""
    from mediated_transfer.sweep.faults import Fault

    failed = [r._return_value for r in returns if r.status == JobStatus.FAILED]
    faults = [f for f in failed if isinstance(f, Fault)]
    if faults:
        n = len(failed) - 1
        others = f" ({n} other run{'s' if n > 1 else ''} failed too)" if n else ""
        raise SystemExit(f"{faults[0]}{others}")
