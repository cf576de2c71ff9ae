"""One job of a command: reuse or compute a learning run, write its result, log it to MLflow,
print its progress line (the entry point, app.py, and the launchers call it).

Each job runs its learning run unless its folder already holds the result, writes the result
there, logs it to MLflow and prints a progress line. Folders are deterministic (conf/config.yaml:
hydra.run.dir / hydra.sweep.subdir), so running an interrupted sweep again skips every finished
run and computes only the rest. A folder that another process is computing for the same run is
skipped; one claimed or finished for another configuration (two sweeps of different
configurations sharing it) fails the job in one line naming the differences (``FolderClash``).
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from hydra.errors import CompactHydraException
from omegaconf import DictConfig, OmegaConf

from ..config.compose import ConfigError, first_line
from ..config.spec import comparable, differences, run_spec
from ..provenance import code_version
from ..provenance.judge import RECOMPUTE, SET_ASIDE, judge
from ..results import RunResult
from ..stored.aside import set_aside
from . import faults, progress, tracking
from .claim import claimed, holder
from .identity import run_label, run_name, run_tags
from .interrupted import sigterm_interrupts
from .orphan import guard

log = logging.getLogger("mediated_transfer")


class FolderClash(ConfigError, CompactHydraException):
    """A job's folder holds, or is being computed for, a run of another configuration: two
    sweeps of different configurations share it. One line, which Hydra prints without a
    traceback; the job fails, so the sweep ends non-zero."""


def run_job(cfg: DictConfig, folder: str | os.PathLike, sweep_dir: str | os.PathLike | None = None,
            variant: str = "") -> dict:
    """Run (or skip) the learning run of ``cfg`` in ``folder``, log it, print a progress line.

    ``sweep_dir``: the sweep's folder when part of a sweep (for the overall count and the time
    left), None for a single run. ``variant``: the run's overrides beyond cell and seed
    (sweep/identity.py). Returns a short summary (Hydra's job return value).
    """
    return run_jobs([(cfg, folder, sweep_dir, variant)])[0]


Job = tuple  # (cfg, folder, sweep_dir, variant), as run_job takes them


def run_jobs(jobs: Sequence[Job]) -> list[dict]:
    """``run_job`` for each of ``jobs``: the runs left to compute (the launchers pass runs of one
    table cell, other seeds: lockstep.runs of them) are computed together in one lockstep group
    (lockstep/run.py), each still into its own folder, result and MLflow run. A single run on
    the CPU computes as ``run.execute_run`` (the same curve, bit for bit, as in a group).
    In a pool's worker, the jobs stop (and the worker exits) once its launcher is gone.

    A full disk (or quota, or file size limit) or a damaged MLflow store stops the jobs as a
    ``faults.Fault``: one line naming the run, the file and what to do."""
    try:
        return _run_jobs(jobs)
    except Exception as error:
        fault = job_fault(error, jobs)
        if fault is None:
            raise
        raise fault from None


def job_fault(error: BaseException, jobs: Sequence[Job]) -> faults.Fault | None:
    """``error`` of ``jobs`` as a fault naming its run (the job whose folder holds the file it
    could not write, else the jobs' cell and seeds), if it is one."""
    cfg, folder = jobs[0][0], jobs[0][1]
    store = _settings(cfg).store if cfg.tracking.enabled else None
    fault = faults.store_damaged(error, store) or faults.disk_full(error, store=store, where=folder)
    if fault is None:
        return None
    labels = {run_label(c, v): Path(f).absolute() for c, f, _, v in jobs}
    file = Path(fault.file).absolute() if fault.file else None
    named = [label for label, f in labels.items() if file is not None and file.is_relative_to(f)]
    if named or len(labels) == 1:
        return fault.of((named or list(labels))[0])
    return fault.of(f"{cfg.cell} seed={','.join(str(c.seed) for c, *_ in jobs)}")


def _run_jobs(jobs: Sequence[Job]) -> list[dict]:
    with guard(), contextlib.ExitStack() as claims:
        summaries: list[dict | None] = [None] * len(jobs)
        pending = []
        for i, (cfg, folder, sweep_dir, variant) in enumerate(jobs):
            spec, folder = run_spec(cfg), Path(folder)
            job = _JobRef(cfg, spec, folder, sweep_dir, variant)
            if not claims.enter_context(claimed(folder, job.claim)):
                # Another launch (of this sweep or one that overlaps it) is computing this run,
                # unless it computes another configuration there: then this says so and fails.
                _check_holder(job)
                log.info("%s: being computed by another process, skipped", job.label)
                summaries[i] = job.summary("busy", None, None)
                continue
            found = _reusable(job)
            if found is not None:
                summaries[i] = _report(job, *found)
            else:
                pending.append((i, job))
        for _, job in pending:
            _log_tuned(job.label)
        if pending and (len(pending) > 1 or str(pending[0][1].cfg.lockstep.device) != "cpu"):
            results = _compute_lockstep([job for _, job in pending])
        else:
            results = [_compute(job.cfg, job.spec, job.folder, job.resolved, job.sweep_dir, job.variant)
                       for _, job in pending]
        for (i, job), result in zip(pending, results):
            summaries[i] = _report(job, result, "done", None)
    return summaries  # type: ignore[return-value]


def _log_tuned(label: str) -> None:
    """Which tuned file (Table I's values) the run got, or that none did (config/tuned.py)."""
    from hydra.core.hydra_config import HydraConfig

    from ..config.compose import source_dirs
    from ..config.tuned import tuned_line

    if HydraConfig.initialized():  # composed by Hydra: a command's job, not a direct call
        runtime = HydraConfig.get().runtime
        log.info("%s: %s", label, tuned_line(runtime.choices, source_dirs(runtime.config_sources)))


class _JobRef:
    """One job's config, run, folder and names."""

    def __init__(self, cfg: DictConfig, spec, folder: Path, sweep_dir, variant: str):
        self.cfg, self.spec, self.folder, self.sweep_dir, self.variant = cfg, spec, folder, sweep_dir, variant
        self.label = run_label(cfg, variant)
        resolved = OmegaConf.to_container(cfg, resolve=True)
        assert isinstance(resolved, dict)
        self.resolved = resolved
        # What the job records in its folder's claim while it holds it (sweep/claim.py).
        self.claim = {"sweep": str(cfg.name),
                      "config": json.loads(json.dumps(comparable(spec), sort_keys=True, default=str))}

    def summary(self, status: str, stale: str | None, reward_loss: float | None) -> dict:
        return {"cell": str(self.cfg.cell), "seed": int(self.cfg.seed), "variant": self.variant,
                "status": status, "stale": stale, "reward_loss": reward_loss, "folder": str(self.folder)}


def _check_holder(job: _JobRef) -> None:
    """FolderClash (logged when it happens, one line) if the process holding the job's folder
    recorded another configuration than the job's; nothing if the same, or nothing recorded."""
    other = holder(job.folder)
    if other is None or not isinstance(other["record"].get("config"), dict):
        return
    detail = differences(other["record"]["config"], job.claim["config"], ("the other", "this one"))
    if not detail:
        return
    sweep = other["record"].get("sweep")
    message = (f"{job.folder}: being computed by another process (pid {other['pid']}"
               f"{f', sweep {sweep}' if sweep else ''}) for another configuration ({detail}): two sweeps "
               "of different configurations share this folder; give one of them another paths.root "
               "or paths.sweep_dir")
    log.error("%s", message)
    raise FolderClash(message)


def _reusable(job: _JobRef) -> tuple[RunResult, str, str | None] | None:
    """(result, "exists", why stale) of a finished run in the job's folder that the judge
    (provenance/judge.py) reuses, logged to MLflow from its files unless MLflow has it already;
    None when the run must be computed (a damaged run's files are set aside first, with one
    warning line)."""
    cfg, folder = job.cfg, job.folder
    try:
        verdict = judge(folder, job.spec, rerun_stale=bool(cfg.rerun_stale))
    except ConfigError as other:  # finished by a sweep of another configuration since preflight
        log.error("%s", other)
        raise FolderClash(str(other)) from None
    if verdict.action == SET_ASIDE:
        moved = set_aside(folder)
        log.warning("%s: %s; set aside as %s, computing the run again", job.label, verdict.reason,
                    ", ".join(p.name for p in moved))
        return None
    if verdict.action == RECOMPUTE:
        return None
    found, stale = verdict.result, verdict.stale
    assert found is not None  # reused: current, or reported stale
    if cfg.tracking.enabled:
        tags = run_tags(cfg, folder, job.spec, job.variant, str(found.code.get("digest", "")))
        with tracking.store_write():
            tracking.log_run(_settings(cfg), experiment=str(cfg.name), key=tags["run_key"],
                             run_name=run_name(cfg, job.variant), result=found,
                             params=tracking.flatten(job.resolved), tags=tags, artifacts=tracking.run_artifacts(folder))
    return found, "exists", stale


def _report(job: _JobRef, result: RunResult, status: str, stale: str | None) -> dict:
    """The job's progress line and summary."""
    cfg, sweep_dir = job.cfg, job.sweep_dir
    sweep_name = f"{cfg.name}/{cfg.scale.name}"
    run = "" if sweep_dir is None else job.folder.resolve().relative_to(Path(sweep_dir).resolve()).as_posix()
    log.info("%s", progress.run_line(job.label, result, status, sweep_name,
                                     None if sweep_dir is None else Path(sweep_dir), run, stale))
    return job.summary(status, stale, result.reward_loss)


def _compute_lockstep(jobs: Sequence[_JobRef]) -> list[RunResult]:
    """The jobs' runs computed together; each result is written as soon as its run ends."""
    from ..lockstep.run import execute_lockstep

    cfg = jobs[0].cfg
    _limit_threads(int(cfg.threads_per_run))
    record = {"lockstep_runs": len(jobs), "device": str(cfg.lockstep.device)}
    computing = [_Computing(j.cfg, j.spec, j.folder, j.resolved, j.sweep_dir, j.variant, record)
                 for j in jobs]
    log.info("%s: %d runs in lockstep (seeds %s) on %s", cfg.cell, len(jobs),
             ",".join(str(j.cfg.seed) for j in jobs), record["device"])
    try:
        with sigterm_interrupts():
            return execute_lockstep([j.spec for j in jobs], [c.hooks for c in computing],
                                    on_result=lambda k, result: computing[k].finished(result),
                                    device=record["device"])
    except BaseException as error:
        for c in computing:
            c.stopped(error)
        raise


def _compute(cfg: DictConfig, spec, folder: Path, resolved: dict, sweep_dir, variant: str) -> RunResult:
    """Run the learning run, followed live in MLflow; write its result into ``folder``."""
    from ..run import execute_run

    _limit_threads(int(cfg.threads_per_run))
    job = _Computing(cfg, spec, folder, resolved, sweep_dir, variant)
    try:
        with sigterm_interrupts():
            hooks = job.hooks
            result = execute_run(spec, progress=hooks.progress, progress_every=hooks.progress_every,
                                 on_evaluation=hooks.on_evaluation, on_finish=hooks.on_finish)
            job.finished(result)
    except BaseException as error:
        job.stopped(error)
        raise
    return result


class _Computing:
    """One run while it computes: its callbacks (progress, live MLflow run, saving the learner)
    and what happens to its result."""

    def __init__(self, cfg: DictConfig, spec, folder: Path, resolved: dict, sweep_dir, variant: str,
                 lockstep: dict | None = None):
        from ..lockstep.run import RunHooks
        from ..saved_learner import forget_learner, save_learner

        self.folder, self.resolved, self.lockstep = folder, resolved, lockstep
        self.result: RunResult | None = None
        self.spec = spec
        # The folder's learner must be this run's: an older one goes before the run starts.
        forget_learner(folder)
        save = (lambda learner: save_learner(learner, spec, folder)) if cfg.save_learner else None
        watch = None if sweep_dir is not None else progress.SingleRunProgress(spec)
        self.live = None
        if cfg.tracking.enabled:
            digest = code_version(spec, lockstep=lockstep is not None)["digest"]
            tags = run_tags(cfg, folder, spec, variant, digest)
            try:
                with tracking.store_write():
                    self.live = tracking.LiveRun(_settings(cfg), experiment=str(cfg.name), key=tags["run_key"],
                                                 run_name=run_name(cfg, variant), params=tracking.flatten(resolved),
                                                 tags=tags)
            except Exception as error:  # noqa: BLE001 - the store failed after the sweep's check
                log.warning("%s: not followed in MLflow: %s", run_label(cfg, variant),
                            tracking.not_logged(_settings(cfg), error))

        def evaluated(step: int, mean_reward: float, success_rate: float) -> None:
            if watch is not None:
                watch.evaluated(step, mean_reward, success_rate)
            if self.live is not None:
                self.live.evaluation(step, mean_reward, success_rate)

        self.hooks = RunHooks(progress=watch, progress_every=spec.budget // spec.eval_points,
                              on_evaluation=evaluated, on_finish=save)

    def finished(self, result: RunResult) -> None:
        """Write the result (atomically) and end the MLflow run as finished."""
        result.config = self.resolved
        # The one writer of a run's code version: only the job knows how it was computed
        # (alone, or in a lockstep group, and how the group ran).
        lockstep = self.lockstep is not None
        result.code = {**code_version(self.spec, lockstep=lockstep), **(self.lockstep or {})}
        result.write(self.folder)
        self.result = result
        if self.live is not None:
            self.live.finish(result, tracking.run_artifacts(self.folder))

    def stopped(self, error: BaseException) -> None:
        if self.live is None:
            return
        if self.result is not None:
            # Stopped while its written result was being logged: logged in full, FINISHED (once
            # finished, the live run ignores this).
            self.live.finish(self.result, tracking.run_artifacts(self.folder))
        else:
            self.live.end(tracking.stopped_status(error))


def _settings(cfg: DictConfig) -> tracking.TrackingSettings:
    return tracking.TrackingSettings.from_config(cfg.tracking)


def _limit_threads(threads: int) -> None:
    # Sweeps run one job per core: a run that also spreads over all cores only slows the others.
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=threads)
    if "torch" in sys.modules:
        sys.modules["torch"].set_num_threads(threads)
