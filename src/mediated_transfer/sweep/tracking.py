"""MLflow tracking: one MLflow experiment per table, one MLflow run per learning run, and one
summary run per table cell, the parent of its seeds' runs.

A learning run's MLflow run holds the resolved config as params (less what does not change what
a run computes: ``NOT_PARAMS``), the evaluation curve as the metric series ``mean_reward`` and
``success_rate`` (step = learning step), ``reward_loss`` (L_R) and ``time_to_threshold`` as
metrics, and tags naming its table, cell, sweep, scale and seed. A run that never reaches the
threshold has ``time_to_threshold`` = its budget, so that a sort puts it after every run that
reaches it, and the tag ``time_to_threshold=never`` says which it is.

A cell's summary run (``log_summary``, made by the reports) carries the same two metrics (L_R:
the mean over its runs) and is the parent (``mlflow.parentRunId``) of the cell's runs: it adopts
them when it is logged, and a run logged once it exists is created under it. So the runs list
shows one row per table cell, its seeds folded under it. Each experiment stores a view of that
list with L_R and time to threshold as columns (``RUNS_VIEW``); ``runs_view_links`` gives its
address (MLflow 3's UI opens an experiment on a GenAI overview instead).

A run being computed is followed live (``LiveRun``): its MLflow run is created when training
starts, each evaluation point is logged as it is measured, with its wall-clock time, so a long
run's curve grows in the UI, and the run ends FINISHED with the training's end time, or KILLED
(interrupted) or FAILED (an error). A run found finished on disk but not in MLflow is logged
from its result files (``log_run``).

Logging is idempotent: every run carries a key (its output folder relative to paths.root) and
is only created when no finished run with that key exists; a run left unfinished by an
interruption is deleted and logged again. So re-running a sweep never duplicates a run.

The default store is SQLite. SQLite cannot be initialised by several processes at once, so
``prepare`` creates the store and the experiment once, before a sweep's workers start.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import logging
import math
import os
import signal
import threading
import time
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..results import RunResult
from . import faults
from .claim import open_lock_file

KIND_RUN = "run"
KIND_SUMMARY = "cell_summary"
NEVER = "never"
PARENT = "mlflow.parentRunId"
"""MLflow's tag of a nested run: its parent's run id."""
RUNS_VIEW = "l_r"
"""The share key of the runs view stored in each experiment (as the UI's own "Share" stores one)."""
RUNS_VIEW_STATE = {
    "selectedColumns": ["metrics.`reward_loss`", "metrics.`reward_loss_sem`", "metrics.`time_to_threshold`",
                        "tags.`time_to_threshold`", "metrics.`n_runs`"],
}
"""The runs list a reader compares at a glance: L_R (a cell's: the mean and SEM over its
``n_runs``) and time to threshold beside each name. It keeps MLflow's order (newest first), so
the cells' summaries, logged last, come first with their runs folded under them: sorted by L_R,
the UI would list the best runs before their cells and show them unfolded."""
NOT_PARAMS = frozenset({"paths", "tracking", "threads_per_run", "rerun_stale", "save_learner", "require_tuned", "report",
                        "lockstep.runs", "scale.seeds", "scale.reports_subdir"})
"""Config keys left out of a run's params: where outputs go and how runs are scheduled, which do
not change what a run computes (as conf/config.yaml leaves them out of a variant's name)."""
_MAX_PARAM_LENGTH = 6000  # MLflow's limit on a param value
_BATCH = {"metrics": 1000, "params": 100, "tags": 100}  # MLflow's limits per log_batch call


@dataclass(frozen=True)
class TrackingSettings:
    uri: str
    """MLflow tracking URI: sqlite:///<file> (embedded) or http(s)://<server>."""
    artifact_location: str | None = None
    """Folder for the artifacts of newly created experiments (None: the server decides)."""

    @classmethod
    def from_config(cls, cfg: Mapping[str, Any]) -> "TrackingSettings":
        uri = cfg.get("uri")
        if not uri:
            raise ValueError("tracking.uri is not set; e.g. tracking.uri=http://127.0.0.1:5000 "
                             "(or tracking=sqlite for the embedded store, tracking=none to disable)")
        return cls(str(uri), None if cfg.get("artifact_location") is None else str(cfg["artifact_location"]))

    @property
    def store(self) -> Path | None:
        """The SQLite store's file (None: a server)."""
        return Path(self.uri.removeprefix("sqlite:///")) if self.uri.startswith("sqlite:///") else None

    def client(self):
        from mlflow.tracking import MlflowClient

        logging.getLogger("mlflow.store.db.utils").addFilter(_reraised)
        if self.uri.startswith("sqlite:///"):
            _create_store_file(Path(self.uri.removeprefix("sqlite:///")))
        return MlflowClient(tracking_uri=self.uri)


def _reraised(record: logging.LogRecord) -> bool:
    """MLflow logs each database error of its store with its traceback (80 lines), then raises
    it: the caller reports it (a full disk or a damaged store in one line), so the log goes."""
    return not str(record.msg).startswith("SQLAlchemy database error")


def _create_store_file(db: Path) -> None:
    """Create an SQLite store's file (empty: a valid empty database) with the user's usual mode.
    SQLite would create it 0644 whatever the umask, and its journals take the file's mode: a
    collaborator of the group could not log into a store the other one created."""
    db.parent.mkdir(parents=True, exist_ok=True)
    if db.name in ("", ":memory:"):
        return
    try:
        os.close(os.open(db, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
    except FileExistsError:
        pass


CHECK_TIMEOUT_S = 10
"""How long the check before a command's first run waits for a tracking server (no retries)."""


def prepare(settings: TrackingSettings, experiment: str) -> str:
    """Create the store (if new) and the experiment (if missing); returns its id. Fails within
    seconds when a server does not answer (MLflow would retry for minutes); a damaged SQLite
    store or a full disk as a ``Fault`` naming the store. For a SQLite store this holds a lock
    beside it: two sweeps starting together on a new store would otherwise both create its
    tables, and one would fail."""
    try:
        with _store_lock(settings), _impatient():
            client = settings.client()
            experiment_id = _experiment_id(client, settings, experiment)
            _ensure_view(client, experiment_id, client.get_experiment(experiment_id).tags)
            return experiment_id
    except Exception as error:
        fault = store_fault(settings, error)
        if fault is None:
            raise
        raise fault from None


def store_fault(settings: TrackingSettings, error: BaseException) -> faults.Fault | None:
    """``error`` as the one line of a damaged SQLite store or a full disk, if it is one."""
    return faults.store_damaged(error, settings.store) or faults.disk_full(error, store=settings.store)


def not_logged(settings: TrackingSettings, error: BaseException) -> str:
    """Why a run's MLflow run stopped, and what logs it (a warning's words): the real remedy for
    a damaged store or a full disk; for another error (a server that did not answer), rerunning
    the sweep, which logs every finished run that MLflow lacks."""
    fault = store_fault(settings, error)
    if fault is not None:
        return str(fault)
    text = str(error).strip()
    return f"{type(error).__name__}: {text.splitlines()[0] if text else ''}; rerunning the sweep logs it"


def _ensure_view(client, experiment_id: str, tags: Mapping[str, str]) -> None:
    """Store the runs view in the experiment, as the UI's "Share" of a view does (if missing or
    another)."""
    key, value = f"mlflow.sharedViewState.{RUNS_VIEW}", json.dumps(RUNS_VIEW_STATE)
    if tags.get(key) != value:
        client.set_experiment_tag(experiment_id, key, value)


@contextlib.contextmanager
def _impatient():
    """MLflow's HTTP client without retries and with a short timeout, for this block only."""
    saved = {k: os.environ.get(k) for k in ("MLFLOW_HTTP_REQUEST_MAX_RETRIES", "MLFLOW_HTTP_REQUEST_TIMEOUT")}
    os.environ["MLFLOW_HTTP_REQUEST_MAX_RETRIES"] = "0"
    os.environ["MLFLOW_HTTP_REQUEST_TIMEOUT"] = str(CHECK_TIMEOUT_S)
    try:
        yield
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


@contextlib.contextmanager
def _store_lock(settings: TrackingSettings):
    if not settings.uri.startswith("sqlite:///"):
        yield
        return
    lock = Path(settings.uri.removeprefix("sqlite:///") + ".lock")
    lock.parent.mkdir(parents=True, exist_ok=True)
    fd = open_lock_file(lock)  # the umask's mode: a collaborator of the group prepares the store too
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)  # waits for the other: creating the tables takes seconds
        yield
    finally:
        os.close(fd)  # releases the lock


def run_artifacts(folder: Path) -> list[Path]:
    """A run's files logged with its MLflow run."""
    files = [folder / "result.json", folder / "curve.csv"]
    files += sorted((folder / ".hydra").glob("*.yaml"))
    return [f for f in files if f.is_file()]

@contextlib.contextmanager
def store_write():
    """The ``with`` block writes to the store whole: Ctrl-C or SIGTERM arriving meanwhile takes
    effect as it ends. Interrupted half-way, an SQLite write leaves this process holding the
    database's lock, so the run's last write (ending it KILLED) would wait the busy timeout
    (20 s) and fail, the MLflow run left RUNNING. Only the main thread can hold signals back;
    elsewhere the block runs unchanged."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held: list[int] = []
    caught = (signal.SIGINT, signal.SIGTERM)
    previous = {s: signal.signal(s, lambda signum, frame: held.append(signum)) for s in caught}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        for s in dict.fromkeys(held):
            signal.raise_signal(s)  # now, to the handler it was meant for


def _experiment_id(client, settings: TrackingSettings, name: str) -> str:
    from mlflow.exceptions import MlflowException

    found = client.get_experiment_by_name(name)
    if found is not None:
        if found.lifecycle_stage == "deleted":
            client.restore_experiment(found.experiment_id)
        return found.experiment_id
    location = None
    if settings.artifact_location is not None:
        # One folder per experiment (table), as MLflow's own file layout has it.
        location = (Path(settings.artifact_location).resolve() / name).as_uri()
    try:
        experiment_id = client.create_experiment(name, artifact_location=location)
        _ensure_view(client, experiment_id, {})
        return experiment_id
    except MlflowException:
        # Created meanwhile by another process.
        found = client.get_experiment_by_name(name)
        if found is None:
            raise
        return found.experiment_id


def log_run(
    settings: TrackingSettings,
    experiment: str,
    key: str,
    run_name: str,
    result: RunResult,
    params: Mapping[str, Any],
    tags: Mapping[str, str],
    artifacts: Iterable[Path] = (),
) -> str:
    """Log one learning run from its result unless a finished MLflow run with ``key`` exists;
    returns its id. (A run computed in this process is logged live instead: ``LiveRun``.)"""
    from mlflow.entities import Metric

    client = settings.client()
    experiment_id = _experiment_id(client, settings, experiment)
    existing = _existing(client, experiment_id, key)
    if existing is not None:
        return existing
    metrics = [Metric("mean_reward", float(r), 0, int(s)) for s, r in zip(result.steps, result.mean_reward)]
    metrics += [Metric("success_rate", float(p), 0, int(s)) for s, p in zip(result.steps, result.success_rate)]
    metrics += _result_metrics(result, timestamp=0)
    all_tags = {**tags, **_result_tags(result)}
    parent = _cell_summary(client, experiment_id, tags)
    if parent is not None:
        all_tags[PARENT] = parent
    return _create(client, experiment_id, key, run_name, metrics, params, all_tags, artifacts)


class LiveRun:
    """The MLflow run of a learning run being computed, logged as it goes.

    Created RUNNING (start time: now) when training starts, after any unfinished run with the
    same key (an earlier interruption) is deleted; ``evaluation`` logs a point of the curve
    with its wall-clock time; ``finish`` logs the result's metrics and artifacts and ends it
    FINISHED; ``end("KILLED" | "FAILED")`` ends it early. A run that already has a finished
    MLflow run (another process logged it) is not followed: every call does nothing.
    """

    def __init__(self, settings: TrackingSettings, experiment: str, key: str, run_name: str,
                 params: Mapping[str, Any], tags: Mapping[str, str]):
        from mlflow.entities import Param

        self.settings = settings
        self.client = client = settings.client()
        experiment_id = _experiment_id(client, settings, experiment)
        self.run_id: str | None = None
        if _existing(client, experiment_id, key) is not None:
            return
        parent = _cell_summary(client, experiment_id, tags)
        tags = {**{k: str(v) for k, v in tags.items()}, "kind": KIND_RUN, "run_key": key,
                "run_key_hash": key_hash(key), **({PARENT: parent} if parent else {})}
        self.run_id = client.create_run(experiment_id, run_name=run_name, tags=tags).info.run_id
        params_list = [Param(k, v) for k, v in params.items()]
        for i in range(0, len(params_list), _BATCH["params"]):
            client.log_batch(self.run_id, params=params_list[i:i + _BATCH["params"]])

    @classmethod
    def resume(cls, settings: TrackingSettings, run_id: str) -> "LiveRun":
        """The live run ``run_id``, left RUNNING by a process that is gone, to end it."""
        live = cls.__new__(cls)
        live.settings, live.client, live.run_id = settings, settings.client(), run_id
        return live

    def evaluation(self, step: int, mean_reward: float, success_rate: float) -> None:
        from mlflow.entities import Metric

        now = _now_ms()
        self._safely(lambda run_id: self.client.log_batch(run_id, metrics=[
            Metric("mean_reward", float(mean_reward), now, int(step)),
            Metric("success_rate", float(success_rate), now, int(step))]))

    def finish(self, result: RunResult, artifacts: Iterable[Path] = ()) -> None:
        def log(run_id: str) -> None:
            metrics = _result_metrics(result, timestamp=_now_ms())
            for i in range(0, len(metrics), _BATCH["metrics"]):
                self.client.log_batch(run_id, metrics=metrics[i:i + _BATCH["metrics"]])
            for k, v in _result_tags(result).items():
                self.client.set_tag(run_id, k, v)
            _log_artifacts(self.client, run_id, artifacts)

        self._safely(log)
        # Last: a run interrupted before this is recognised and redone. A run stopped as failed
        # (its learner diverged) ends FAILED, its reason in the tag ``failure``.
        self.end("FAILED" if result.failed else "FINISHED")

    def end(self, status: str) -> None:
        self._safely(lambda run_id: self.client.set_terminated(run_id, status, end_time=_now_ms()))
        self.run_id = None

    def _safely(self, log) -> None:
        """Tracking must never cost a run: if the store fails, following stops (one warning,
        saying what logs it: ``not_logged``) and the run goes on; its result file is written."""
        if self.run_id is None:
            return
        try:
            with store_write():
                log(self.run_id)
        except Exception as error:  # noqa: BLE001 - any store or network error
            warnings.warn(f"MLflow stopped following this run, its result is kept: {not_logged(self.settings, error)}",
                          RuntimeWarning, stacklevel=2)
            self.run_id = None


def _now_ms() -> int:
    return int(time.time() * 1000)


def _result_metrics(result: RunResult, timestamp: int) -> list:
    from mlflow.entities import Metric

    scalars = {
        "reward_loss": result.reward_loss,
        # Never reached: the budget (and the tag time_to_threshold=never), so a sort can use it.
        "time_to_threshold": result.budget if result.time_to_threshold is None else result.time_to_threshold,
        "final_reward": result.mean_reward[-1] if result.mean_reward else None,
        "learning_steps_per_s": result.learning_steps_per_s,
        "wall_time_s": result.wall_time_s,
        "source_tasks_solved": result.source_tasks_solved,
        "source_phase_end": result.source_phase_end,
        "first_target_reward_step": result.first_target_reward_step,
        **{f"learner.{k}": v for k, v in result.learner_stats.items()},
    }
    return [Metric(k, _rounded(v), timestamp, 0) for k, v in scalars.items() if _is_number(v)]


def _rounded(value: Any) -> float:
    """A scalar as the UI shows it: 18.3, not the 18.299999999999997 a float sum leaves."""
    return round(float(value), 9)


def _result_tags(result: RunResult) -> dict[str, str]:
    tags = {"kind": KIND_RUN}
    # MLflow's own source tags: the UI shows the commit a run was computed with.
    if result.code.get("commit"):
        tags["mlflow.source.git.commit"] = str(result.code["commit"])
        tags["mlflow.source.name"] = "mediated_transfer"
        tags["mlflow.source.type"] = "LOCAL"
    if result.code.get("dirty") is not None:
        tags["code_dirty"] = str(bool(result.code["dirty"])).lower()
    if result.time_to_threshold is None:
        tags["time_to_threshold"] = NEVER
    if result.failed:
        tags["failure"] = str(result.failure)[:5000]
    return tags


def log_summary(
    settings: TrackingSettings,
    experiment: str,
    key: str,
    run_name: str,
    summary: Mapping[str, Any],
    tags: Mapping[str, str],
    artifacts: Iterable[Path] = (),
    fingerprint: str = "",
) -> str:
    """Log the summary run of a table cell (output of metrics.summarise_runs), the parent of the
    cell's runs (same ``sweep``, ``cell`` and ``variant`` tags).

    Its key identifies the cell of a sweep. An existing summary with the same ``fingerprint``
    (the data it summarises) is kept; one with another fingerprint is replaced, so a report
    rebuilt after more runs finished updates the summary instead of adding a second one. Either
    way the cell's runs are its children afterwards (those of a replaced summary move over
    before it is deleted).
    """
    client = settings.client()
    experiment_id = _experiment_id(client, settings, experiment)
    existing = _runs_with_key(client, experiment_id, key)
    kept = next((run.info.run_id for run in existing if run.info.status == "FINISHED"
                 and run.data.tags.get("fingerprint") == fingerprint), None)
    if kept is None:
        kept = _create_summary(client, experiment_id, key, run_name, summary, tags, artifacts, fingerprint)
    _adopt(client, experiment_id, kept, tags)
    for run in existing:
        if run.info.run_id != kept:
            client.delete_run(run.info.run_id)
    return kept


def _create_summary(client, experiment_id, key, run_name, summary, tags, artifacts, fingerprint) -> str:
    from mlflow.entities import Metric

    steps = [int(s) for s in summary["steps"]]
    metrics = [Metric("mean_reward", float(r), 0, s) for s, r in zip(steps, summary["mean_curve"])]
    metrics += [Metric("mean_reward_sem", float(e), 0, s) for s, e in zip(steps, summary["sem_curve"])]
    scalars = {k: summary.get(k) for k in (
        "n_runs", "reward_loss_mean", "reward_loss_sem", "final_reward_mean", "final_reward_sem",
        "time_to_threshold", "time_to_threshold_median", "runs_reaching_threshold")}
    # The columns a cell shares with its runs: L_R (here the mean over the runs) and the time
    # to threshold (of the mean curve; never reached: the last step, and the tag).
    scalars["reward_loss"] = summary.get("reward_loss_mean")
    if scalars["time_to_threshold"] is None and steps:
        scalars["time_to_threshold"] = steps[-1]
    metrics += [Metric(k, _rounded(v), 0, 0) for k, v in scalars.items() if _is_number(v, allow_nan=True)]
    all_tags = {**tags, "kind": KIND_SUMMARY, "fingerprint": fingerprint}
    if summary.get("time_to_threshold") is None:
        all_tags["time_to_threshold"] = NEVER
    return _create(client, experiment_id, key, run_name, metrics, {}, all_tags, artifacts)


def _cell_filter(tags: Mapping[str, str], kind: str) -> str | None:
    """Search filter for the runs of ``kind`` in the table cell that ``tags`` name (sweep and
    cell); None when they name none, or hold a quote (which a filter cannot)."""
    sweep, cell = tags.get("sweep"), tags.get("cell")
    if not sweep or not cell or "'" in f"{sweep}{cell}":
        return None
    return f"tags.kind = '{kind}' and tags.sweep = '{sweep}' and tags.cell = '{cell}'"


def _cell_summary(client, experiment_id: str, tags: Mapping[str, str]) -> str | None:
    """The run id of the summary of the table cell a run's ``tags`` name, if it has one."""
    where = _cell_filter(tags, KIND_SUMMARY)
    if where is None:
        return None
    found = [r for r in _search(client, experiment_id, where)
             if r.data.tags.get("variant") == tags.get("variant") and r.info.status == "FINISHED"]
    return found[0].info.run_id if found else None


def _adopt(client, experiment_id: str, parent_id: str, tags: Mapping[str, str]) -> None:
    """Make the summary ``parent_id`` the parent of every run of its table cell."""
    where = _cell_filter(tags, KIND_RUN)
    if where is None:
        return
    for run in _search(client, experiment_id, where):
        if run.data.tags.get("variant") == tags.get("variant") and run.data.tags.get(PARENT) != parent_id:
            client.set_tag(run.info.run_id, PARENT, parent_id)


def _search(client, experiment_id: str, filter_string: str) -> list:
    from mlflow.entities import ViewType

    runs, token = [], None
    while True:
        page = client.search_runs([experiment_id], filter_string, ViewType.ACTIVE_ONLY,
                                  max_results=1000, page_token=token)
        runs += list(page)
        token = page.token
        if not token:
            return runs


def running_runs(client, experiment_id: str) -> list:
    """The learning runs of an experiment whose MLflow run is RUNNING."""
    return _search(client, experiment_id, f"attributes.status = 'RUNNING' and tags.kind = '{KIND_RUN}'")


def find_runs(settings: TrackingSettings, experiment: str, filter_string: str = "") -> list:
    """Active MLflow runs of ``experiment`` matching ``filter_string`` (MLflow's search syntax)."""
    client = settings.client()
    found = client.get_experiment_by_name(experiment)
    return [] if found is None else _search(client, found.experiment_id, filter_string)


def flatten(config: Mapping[str, Any], prefix: str = "", leave_out: frozenset[str] = NOT_PARAMS) -> dict[str, str]:
    """Nested config -> {"algorithm.lambda_": "0.9", ...}: MLflow params are flat strings. The
    dotted keys in ``leave_out`` (and what is under them) are left out."""
    flat: dict[str, str] = {}
    for key, value in config.items():
        name = f"{prefix}{key}"
        if name in leave_out:
            continue
        if isinstance(value, Mapping):
            flat.update(flatten(value, f"{name}.", leave_out))
        else:
            flat[name] = str(value)[:_MAX_PARAM_LENGTH]
    return flat


def key_hash(key: str) -> str:
    """Searchable form of a run key (a key may hold quotes, which a filter string cannot)."""
    return hashlib.sha256(key.encode()).hexdigest()[:32]


def _runs_with_key(client, experiment_id: str, key: str) -> list:
    from mlflow.entities import ViewType

    return list(client.search_runs([experiment_id], f"tags.run_key_hash = '{key_hash(key)}'",
                                   ViewType.ACTIVE_ONLY, max_results=100))


def _existing(client, experiment_id: str, key: str) -> str | None:
    runs = _runs_with_key(client, experiment_id, key)
    # Complete: FINISHED, or FAILED with its reason (a diverged run is an outcome, not an
    # interruption); anything else was interrupted.
    finished = [r.info.run_id for r in runs if r.info.status == "FINISHED"
                or (r.info.status == "FAILED" and "failure" in r.data.tags)]
    for run in runs:
        if run.info.run_id not in finished[:1]:
            # Left unfinished by an interruption (or a duplicate): log it again cleanly.
            client.delete_run(run.info.run_id)
    return finished[0] if finished else None


def _create(client, experiment_id, key, run_name, metrics, params, tags, artifacts) -> str:
    from mlflow.entities import Param

    tags = {**{k: str(v) for k, v in tags.items()}, "run_key": key, "run_key_hash": key_hash(key)}
    run = client.create_run(experiment_id, run_name=run_name, tags=tags)
    run_id = run.info.run_id
    params_list = [Param(k, v) for k, v in params.items()]
    try:
        for i in range(0, len(metrics), _BATCH["metrics"]):
            client.log_batch(run_id, metrics=metrics[i:i + _BATCH["metrics"]])
        for i in range(0, len(params_list), _BATCH["params"]):
            client.log_batch(run_id, params=params_list[i:i + _BATCH["params"]])
        _log_artifacts(client, run_id, artifacts)
    except BaseException as error:  # interrupted while logging: not left RUNNING; a rerun redoes it
        client.set_terminated(run_id, stopped_status(error))
        raise
    # The status last: a run interrupted before this line is recognised and redone.
    client.set_terminated(run_id, "FAILED" if "failure" in tags else "FINISHED")
    return run_id


def stopped_status(error: BaseException) -> str:
    """MLflow status of a run stopped by ``error``: Ctrl-C or SIGTERM (a scheduler's kill, a
    timeout) is KILLED; anything else FAILED."""
    return "KILLED" if isinstance(error, (KeyboardInterrupt, SystemExit)) else "FAILED"


def _log_artifacts(client, run_id: str, artifacts: Iterable[Path]) -> None:
    for path in artifacts:
        # Hydra's record of the run (config, overrides) goes into a folder of its own.
        client.log_artifact(run_id, str(path), "hydra" if Path(path).parent.name == ".hydra" else None)


def _is_number(value: Any, allow_nan: bool = False) -> bool:
    if value is None or isinstance(value, bool):
        return False
    try:
        number = float(value)
    except (TypeError, ValueError):
        return False
    return math.isfinite(number) or (allow_nan and math.isnan(number))


def runs_view_links(settings: TrackingSettings, ui: str) -> list[str]:
    """``<experiment>: <url>`` of each experiment's runs list in the UI at ``ui``, in the stored
    view (``RUNS_VIEW``), which this stores first in experiments made before it existed."""
    client = settings.client()
    links = []
    for e in client.search_experiments():
        if e.name != "Default":
            _ensure_view(client, e.experiment_id, e.tags)
            links.append(f"{e.name}: {ui.rstrip('/')}/#/experiments/{e.experiment_id}/runs"
                         f"?viewStateShareKey={RUNS_VIEW}")
    return links


if __name__ == "__main__":  # `make mlflow-ui` prints where the runs are before serving them
    import sys

    for line in runs_view_links(TrackingSettings(sys.argv[1]), sys.argv[2]):
        print(line)
