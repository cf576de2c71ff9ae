"""The Optuna study of one search space: stored, resumable, run by N worker processes.

The study lives in ``<root>/tuning/<learner>/`` (paper scale; other scales in a sub-folder
named after the scale): ``study.db`` (Optuna's SQLite storage) and ``trials.csv`` (export.py).
Running the same command again continues the study up to its trial count. Workers send a
heartbeat; a trial whose worker died (killed, machine lost) is failed after a grace period and
queued again with the same values, and one interrupted by Ctrl-C is queued again at the next
launch, so no trial is lost. The provisional defaults are queued as the first trial.
A random trial that can no longer beat the best finished one is stopped early (objective.py)
and stored as PRUNED, with its lower bound as its value: it counts toward the trial count, and
the search selects exactly the trial it would select without stopping any.
"""

from __future__ import annotations

import multiprocessing
import statistics
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import optuna
from optuna.storages import RDBStorage, RetryHeartbeatStaleTrialCallback, fail_stale_trials
from optuna.trial import TrialState

from ..sweep.orphan import launcher_watch
from ..sweep.progress import duration
from ..sweep.tracking import TrackingSettings
from . import mlflow_log
from .trials import STUDY_FILE, write_trials_csv
from .objective import StoppedEarly, evaluate
from .sampler import TrialSeededRandomSampler
from .space import SearchSpace

# Heartbeats and their retry callback are marked experimental (since Optuna 2.8/2.9) but are
# the documented way to redo the trials of dead workers.
warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)

PAPER_SCALE = "paper"
"""Studies at this scale are the ones Table I is built from: tuning/<learner>/ itself."""
HEARTBEAT_S = 15
"""A running trial writes a heartbeat this often ..."""
GRACE_S = 60
"""... and counts as dead (failed, then queued again) after this long without one."""
POLL_S = 5
"""A worker with nothing to start checks this often whether the others' trials finished or died."""
MAX_RETRIES = 10
"""A trial is redone at most this often (a trial that keeps failing is a bug to look at). Not
fewer: a DQN trial can outlast several working sessions' ends, each of which interrupts it."""
DEFAULTS, RANDOM = "defaults", "random"
"""The role of a trial: the provisional defaults (queued first) or a random draw."""


class StudyMismatchError(ValueError):
    """The stored study was run with another search space than the file now describes."""


@dataclass(frozen=True)
class StudyPlan:
    space: SearchSpace
    folder: Path
    """Where study.db and trials.csv live."""
    trials: int
    """Finished trials the study runs to."""
    workers: int = 1
    tracking: TrackingSettings | None = None
    """MLflow store of the trial runs; None: no tracking."""
    parent_run_id: str | None = None
    """The study's MLflow run (set by prepare)."""

    @property
    def name(self) -> str:
        return f"{self.space.learner}/{self.space.scale}"


def study_folder(root: Path, space: SearchSpace) -> Path:
    folder = Path(root) / "tuning" / space.learner
    return folder if space.scale == PAPER_SCALE else folder / space.scale


def storage(folder: Path) -> RDBStorage:
    return RDBStorage(
        f"sqlite:///{Path(folder) / STUDY_FILE}",
        # Workers share the file: wait for its lock rather than fail.
        engine_kwargs={"connect_args": {"timeout": 120}},
        heartbeat_interval=HEARTBEAT_S,
        grace_period=GRACE_S,
        heartbeat_stale_trial_callback=RetryHeartbeatStaleTrialCallback(max_retry=MAX_RETRIES),
    )


def load_study(plan: StudyPlan) -> optuna.Study:
    optuna.logging.set_verbosity(optuna.logging.WARNING)  # the progress lines say it all
    return optuna.create_study(
        study_name=plan.space.learner,
        storage=storage(plan.folder),
        direction="minimize",  # the reward loss
        sampler=TrialSeededRandomSampler(plan.space.sampler_seed),
        load_if_exists=True,
    )


def prepare(plan: StudyPlan) -> StudyPlan:
    """Once, before the workers start: create or check the study, queue the provisional
    defaults and every interrupted trial, create the MLflow parent run and log any finished
    trial it lacks. Returns the plan with the parent run's id."""
    plan.folder.mkdir(parents=True, exist_ok=True)
    study = load_study(plan)
    identity = plan.space.identity()
    stored = study.user_attrs.get("search_space")
    if stored is None:
        study.set_user_attr("search_space", identity)
    elif stored != identity:
        differ = sorted(k for k in identity if stored.get(k) != identity[k])
        raise StudyMismatchError(
            f"{plan.folder / STUDY_FILE} was run with another search space ({', '.join(differ)} "
            f"differ: stored {[stored.get(k) for k in differ]}, now {[identity[k] for k in differ]}); "
            "restore the file's values, or move the study away to start a new one"
        )
    fail_stale_trials(study)
    _queue_interrupted(study)
    # Queued before any random trial, so the defaults are trial 0 of a new study.
    study.enqueue_trial(dict(plan.space.defaults), user_attrs={"role": DEFAULTS}, skip_if_exists=True)
    if plan.tracking is None:
        return plan
    key = mlflow_log.study_key(plan.space.learner, plan.space.scale)
    parent = mlflow_log.prepare_study_run(plan.tracking, key, {
        "learner": plan.space.learner, "scale": plan.space.scale,
        "seeds": ",".join(map(str, plan.space.seeds)), "search_space": plan.space.path.name})
    mlflow_log.log_trials(plan.tracking, parent, key, _finished(study))
    return StudyPlan(plan.space, plan.folder, plan.trials, plan.workers, plan.tracking, parent)


def _queue_interrupted(study: optuna.Study) -> None:
    # Ctrl-C marks the running trial FAIL without a retry; a dead worker's trial was retried
    # by the heartbeat callback already (its number is in the copy's retry history).
    trials = study.get_trials(deepcopy=False)
    retried = {n for t in trials for n in RetryHeartbeatStaleTrialCallback.retry_history(t)}
    retry = RetryHeartbeatStaleTrialCallback(max_retry=MAX_RETRIES)
    for trial in trials:
        if trial.state == TrialState.FAIL and trial.number not in retried:
            retry(study, trial)


FINISHED = (TrialState.COMPLETE, TrialState.PRUNED)
"""Trials that count toward the study's trial count: run to the end, or stopped early."""


def _finished(study: optuna.Study) -> list:
    return study.get_trials(deepcopy=False, states=FINISHED)


def _complete(trials: list) -> list:
    return [t for t in trials if t.state == TrialState.COMPLETE]


def best_objective(study: optuna.Study) -> float | None:
    """The lowest objective of the trials run to the end; None before the first."""
    values = [t.value for t in _complete(_finished(study))]
    return min(values) if values else None


def objective(space: SearchSpace):
    def run_trial(trial: optuna.Trial) -> float:
        values = {}
        for p in space.params:
            if p.kind == "choice":
                values[p.key] = trial.suggest_categorical(p.key, list(p.choices))
            elif p.kind == "int":
                values[p.key] = trial.suggest_int(p.key, int(p.low), int(p.high), log=p.log)
            else:
                values[p.key] = trial.suggest_float(p.key, float(p.low), float(p.high), log=p.log)
        if "role" not in trial.user_attrs:
            trial.set_user_attr("role", RANDOM)
        # The defaults run to the end: Table I compares the best with their objective.
        ceiling = None if trial.user_attrs["role"] == DEFAULTS else (lambda: best_objective(trial.study))
        try:
            reward_loss, record = evaluate(space, values, ceiling)
        except StoppedEarly as stop:
            for name, value in stop.record.items():
                trial.set_user_attr(name, value)
            trial.set_user_attr("stopped_early", {"lower_bound": stop.lower_bound, "best": stop.ceiling,
                                                  "seed": stop.seed, "step": stop.step})
            trial.report(stop.lower_bound, step=0)  # Optuna stores it as the PRUNED trial's value
            raise optuna.TrialPruned(str(stop)) from None
        for name, value in record.items():
            trial.set_user_attr(name, value)
        return reward_loss

    return run_trial


def work(plan: StudyPlan) -> None:
    """One worker: run trials until the study has ``plan.trials`` finished ones.

    A new trial starts only while finished + running trials are fewer than the count, so the
    study ends at the count (with several workers, at most workers - 1 more when they start
    together). Trials of others still running: wait for them, and redo any that died.
    """
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)  # one worker, one core
    study = load_study(plan)
    started = time.time()
    orphaned = launcher_watch()
    while True:
        if orphaned():
            return  # the study's process was killed: an orphaned worker stops (a trial it ran stops itself)
        fail_stale_trials(study)
        trials = study.get_trials(deepcopy=False)
        counts = {s: sum(t.state == s for t in trials) for s in TrialState}
        finished = sum(counts[s] for s in FINISHED)
        if finished >= plan.trials:
            return
        if counts[TrialState.WAITING] == 0 and finished + counts[TrialState.RUNNING] >= plan.trials:
            time.sleep(POLL_S)
            continue
        try:
            study.optimize(objective(plan.space), n_trials=1,
                           callbacks=[lambda s, t: after_trial(plan, s, t, started)])
        except ValueError as error:
            # Two workers that start together can both pop the one queued (retried) trial from
            # SQLite; the second to finish finds it COMPLETE. Its result is the same (same values,
            # same seeds), so it is dropped and the worker goes on.
            if "Cannot tell a COMPLETE trial" not in str(error):
                raise


def after_trial(plan: StudyPlan, study: optuna.Study, trial, started: float) -> None:
    if trial.state not in FINISHED:
        return
    finished = _finished(study)
    write_trials_csv(study, plan.folder)
    if plan.tracking is not None:
        key = mlflow_log.study_key(plan.space.learner, plan.space.scale)
        mlflow_log.log_trial(plan.tracking, plan.parent_run_id, key, trial)
        mlflow_log.log_study_progress(plan.tracking, plan.parent_run_id, len(finished),
                                      best_objective(study), _defaults_objective(finished))
    print(progress_line(plan, trial, finished), flush=True)


def _defaults_objective(finished: list) -> float | None:
    values = [t.value for t in finished if t.user_attrs.get("role") == DEFAULTS]
    return values[0] if values else None


def progress_line(plan: StudyPlan, trial, finished: list) -> str:
    """``[rbf/paper 5/120, ~1h30m left] trial 4 (random): L_R 150.3 (...); best ...``"""
    best = min(_complete(finished), key=lambda t: t.value)
    durations = [(t.datetime_complete - t.datetime_start).total_seconds() for t in finished]
    left = max(plan.trials - len(finished), 0) * statistics.median(durations) / plan.workers
    per_seed = ", ".join(f"{v:.1f}" for v in trial.user_attrs.get("reward_loss", []))
    stop = trial.user_attrs.get("stopped_early")
    result = (f"L_R {trial.value:.1f} (seeds {per_seed})" if stop is None else
              f"stopped early at seed {stop['seed']}, step {stop['step']:,}: L_R >= {stop['lower_bound']:.1f}"
              + (f" (seeds done {per_seed})" if per_seed else ""))
    defaults = _defaults_objective(finished)
    return (f"[{plan.name} {len(finished)}/{plan.trials}, ~{duration(left)} left] "
            f"trial {trial.number} ({trial.user_attrs.get('role')}): {result}; "
            f"best {best.value:.1f} (trial {best.number})"
            + ("" if defaults is None else f", defaults {defaults:.1f}"))


def run_study(plan: StudyPlan) -> optuna.Study:
    """Prepare, run ``plan.workers`` worker processes (in this process when 1), export trials.csv."""
    plan = prepare(plan)
    study = load_study(plan)
    done = len(_finished(study))
    print(f"[{plan.name}] study {plan.folder / STUDY_FILE}: {done}/{plan.trials} trials finished, "
          f"{plan.workers} worker(s), seeds {list(plan.space.seeds)}", flush=True)
    if plan.workers == 1:
        work(plan)
    else:
        # spawn: each worker imports afresh (no forked SQLite connections or numba state).
        context = multiprocessing.get_context("spawn")
        processes = [context.Process(target=work, args=(plan,), name=f"tune-worker-{i}")
                     for i in range(plan.workers)]
        for process in processes:
            process.start()
        for process in processes:
            process.join()
        failed = [p.name for p in processes if p.exitcode != 0]
        if failed:
            raise RuntimeError(f"worker(s) {', '.join(failed)} failed; run the command again to resume")
    write_trials_csv(study, plan.folder)
    return study
