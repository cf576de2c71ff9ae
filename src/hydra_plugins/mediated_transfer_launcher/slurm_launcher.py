"""``hydra/launcher=slurm``: hydra-submitit-launcher's SLURM launcher, made for sweeps of runs.

Hydra instantiates launchers only from the ``hydra_plugins`` package, hence this module; the
parts live in mediated_transfer.slurm. On top of submitit's launcher it
- checks the request against the partition first (sinfo), in one line,
- settles finished runs here instead of submitting jobs that only skip them,
- packs ``runs_per_job`` runs into each job (Python starts once per job, not per run), or, when
  ``lockstep.runs`` (or a GPU device) asks for lockstep groups, one group of a cell's seeds per
  job, trained together (mediated_transfer.lockstep),
- attaches to the jobs of an earlier launch that are still queued (the sweep's ledger),
- waits with progress lines in this terminal, or returns at once with ``wait=false``,
- ends with one line per failed job or run instead of submitit's tracebacks.
"""

# No `from __future__ import annotations`: Hydra's plugin scan executes this module outside
# sys.modules, where dataclasses cannot resolve string annotations.
import logging
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

from hydra.core.config_store import ConfigStore
from hydra.core.singleton import Singleton
from hydra.core.utils import JobReturn, JobStatus, setup_globals
from hydra_plugins.hydra_submitit_launcher.config import BaseQueueConf, SlurmQueueConf
from hydra_plugins.hydra_submitit_launcher.submitit_launcher import BaseSubmititLauncher, SlurmLauncher
from omegaconf import OmegaConf, open_dict

log = logging.getLogger("mediated_transfer")

# Keys of this launcher that are not sbatch's (submitit would refuse them).
OWN_KEYS = ("runs_per_job", "progress_every_s", "wait")


@dataclass
class MediatedSlurmConf(SlurmQueueConf):
    _target_: str = "hydra_plugins.mediated_transfer_launcher.slurm_launcher.MediatedSlurmLauncher"
    # Runs carried by one job, one after the other (each keeps its folder and MLflow run).
    runs_per_job: int = 1
    # Seconds between checks of the queue (squeue) and progress lines while waiting.
    progress_every_s: int = 60
    # false: submit, record the jobs and return; the same command run again waits for them.
    wait: bool = True


ConfigStore.instance().store(group="hydra/launcher", name="mediated_slurm", node=MediatedSlurmConf(),
                             provider="mediated_transfer")


class MediatedSlurmLauncher(SlurmLauncher):
    def __init__(self, **params: Any) -> None:
        super().__init__(**params)
        self.own = {key: self.params.pop(key) for key in OWN_KEYS}

    def run_group(self, group: list[tuple[list[str], int, str]],
                  singleton_state: dict) -> list[tuple[str, JobReturn]]:
        """In the SLURM job: the group's runs one after the other, each as its own Hydra job
        (its folder, log and MLflow run); a failed run does not stop the others."""
        from mediated_transfer.slurm.errors import reached_time_limit

        done = []
        for overrides, index, run in group:
            if done and reached_time_limit(done[-1][1]):
                # submitit's signal before the time limit stopped a run: the next ones would be
                # killed halfway; they are reported as not started, and a rerun computes them.
                ret = JobReturn()
                ret.status, ret._return_value = JobStatus.FAILED, TimeoutError("not started: the job reached its time limit")
                done.append((run, ret))
                continue
            done.append((run, self(overrides, "hydra.sweep.dir", index, f"job_id_for_{index}", singleton_state)))
        return done

    def run_lockstep_group(self, group: list[tuple[list[str], int, str]],
                           singleton_state: dict) -> list[tuple[str, JobReturn]]:
        """In the SLURM job: the group's runs as Hydra jobs (folders, logs, MLflow runs),
        computed together in lockstep (mediated_transfer.sweep.groups.run_group)."""
        import submitit

        from mediated_transfer.sweep.groups import run_group

        Singleton.set_state(singleton_state)
        setup_globals()
        jobs = []
        for overrides, index, _ in group:
            sweep_config = self.hydra_context.config_loader.load_sweep_config(self.config, overrides)
            with open_dict(sweep_config.hydra.job) as job:
                job.id = submitit.JobEnvironment().job_id
                sweep_config.hydra.job.num = index
            jobs.append((sweep_config, self.hydra_context))
        return [(run, ret) for (_, _, run), ret in zip(group, run_group(jobs))]

    def launch(self, job_overrides: Sequence[Sequence[str]], initial_job_idx: int) -> Sequence[JobReturn]:
        from mediated_transfer.config.compose import ConfigError
        from mediated_transfer.slurm.cluster import ClusterError

        try:
            return self._launch(job_overrides, initial_job_idx)
        except (ClusterError, ConfigError) as error:
            raise SystemExit(f"SLURM: {error}") from None

    def _launch(self, job_overrides: Sequence[Sequence[str]], initial_job_idx: int) -> Sequence[JobReturn]:
        from mediated_transfer.slurm import cluster, errors, jobs, watch
        from mediated_transfer.slurm.ledger import Ledger

        assert self.config is not None and self.hydra_context is not None
        params, own = self.params, self.own
        cluster.check_request(cluster.partitions(), params.get("partition"), float(params["timeout_min"]),
                              params.get("mem_gb"), params.get("cpus_per_task"))
        runs_per_job = int(own["runs_per_job"])
        sweep_dir = Path(str(self.config.hydra.sweep.dir))
        sweep_name = f"{self.config.name}/{self.config.scale.name}"
        sweep_dir.mkdir(parents=True, exist_ok=True)

        def load(overrides: list[str]):
            return self.hydra_context.config_loader.load_sweep_config(self.config, overrides)

        planned = jobs.plan_runs(job_overrides, initial_job_idx, load)
        finished, pending = jobs.split_finished(planned)
        failed = self._settle(finished, sweep_dir)
        name = {r.folder: r.folder.relative_to(sweep_dir).as_posix() for r in planned}

        ledger = Ledger(sweep_dir)
        queued = cluster.queue() if pending else {}
        live = ledger.live([name[r.folder] for r in pending], queued)
        attached: dict[str, watch.Submitted] = {}
        for run, entry in live.items():
            if entry["job"] not in attached:
                attached[entry["job"]] = watch.Submitted(self._job(entry), [])
            attached[entry["job"]].runs.append(run)
        to_submit = [r for r in pending if name[r.folder] not in live]
        lockstep = jobs.lockstep_groups_of(to_submit)
        groups = lockstep or jobs.group_runs(to_submit, runs_per_job)
        submitted = self._submit(groups, name, errors, lockstep is not None) if groups else []
        per_job = max(len(g) for g in lockstep) if lockstep else runs_per_job
        ledger.record({run: {"job": s.job.job_id, "folder": str(params["submitit_folder"])}
                       for s in submitted for run in s.runs})
        log.info("%s: %d runs; %d finished already (not submitted), %d waited for in %d queued jobs, "
                 "%d submitted in %d jobs (%d runs per job)", sweep_name, len(planned), len(finished),
                 sum(len(s.runs) for s in attached.values()), len(attached), len(to_submit),
                 len(submitted), per_job)
        everything = list(attached.values()) + submitted
        if not everything:
            return self._end([], failed, len(planned))
        if not own["wait"]:
            log.info("%s: not waiting (hydra.launcher.wait=false); the same command again waits for "
                     "these jobs and shows progress", sweep_name)
            return []
        outcome = watch.wait(everything, sweep_dir, sweep_name, float(own["progress_every_s"]),
                             float(params["timeout_min"]), per_job)
        return self._end(outcome.returns, failed + outcome.errors, len(planned))

    def _settle(self, finished: list, sweep_dir: Path) -> list[str]:
        """Finished runs are read back and logged to MLflow if missing, here, exactly as their
        job would (sweep.job.run_job skips them); their progress lines are left out."""
        from mediated_transfer.sweep.job import run_job

        failed = []
        quiet = logging.getLogger("mediated_transfer")
        level = quiet.level
        quiet.setLevel(logging.WARNING)
        try:
            for run in finished:
                variant = str(run.config.hydra.job.override_dirname)
                # A job's task config, as Hydra's run_job hands it over: without the hydra node.
                task = run.config.copy()
                with open_dict(task):
                    del task["hydra"]
                try:
                    run_job(task, run.folder, sweep_dir, variant)
                except Exception as error:  # noqa: BLE001 - one line per run, the others go on
                    failed.append(f"run {run.folder}: {type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''}")
        finally:
            quiet.setLevel(level)
        return failed

    def _executor(self):
        import submitit

        params = dict(self.params)
        executor = submitit.AutoExecutor(cluster=self._EXECUTOR, folder=params.pop("submitit_folder"),
                                         slurm_max_num_timeout=params.pop("max_num_timeout"))
        base = set(OmegaConf.structured(BaseQueueConf).keys())
        executor.update_parameters(**{k if k in base else f"{self._EXECUTOR}_{k}": v for k, v in params.items()})
        return executor

    def _submit(self, groups: list, name: dict, errors, lockstep: bool = False) -> list:
        from submitit.core.utils import FailedJobError, FailedSubmissionError

        from mediated_transfer.slurm import watch
        from mediated_transfer.slurm.cluster import ClusterError

        args = [[(list(r.overrides), r.index, name[r.folder]) for r in group] for group in groups]
        executor = self._executor()
        try:
            run = self.run_lockstep_group if lockstep else self.run_group
            submitted = executor.map_array(run, args, [Singleton.get_state()] * len(args))
        except (FailedJobError, FailedSubmissionError, subprocess.CalledProcessError) as error:
            raise ClusterError(errors.sbatch_error(getattr(error, "output", None) or str(error))) from None
        return [watch.Submitted(job, [run for _, _, run in group]) for job, group in zip(submitted, args)]

    def _job(self, entry: dict):
        from submitit.slurm.slurm import SlurmJob

        return SlurmJob(folder=entry["folder"], job_id=entry["job"])

    def _end(self, returns: list, failed: list[str], total: int) -> list:
        if failed:
            for line in failed:
                log.error("%s", line)
            raise SystemExit(f"SLURM: {len(failed)} of {total} runs or jobs failed (above); run the "
                             "same command again to retry them (finished runs are kept)")
        return returns


# BaseSubmititLauncher is re-exported for Hydra's plugin scan to see its subclass here.
__all__ = ["BaseSubmititLauncher", "MediatedSlurmConf", "MediatedSlurmLauncher"]
