"""MLflow: one parent run per study, one nested run per finished trial.

A trial's run holds its searched values as params, the objective as ``reward_loss``, the mean
curve over the tuning seeds as ``mean_reward`` (step = learning step) and the per-seed values
(``reward_loss.seed_1000``, ``first_target_reward_step.seed_1000``, ...); a trial stopped early
(study.py) holds ``reward_loss_lower_bound`` instead, its finished seeds' values and the tag
``stopped_early``. Runs are keyed by study
and trial number and logged once: a study resumed on another machine (or after a crash between
a trial's end and its logging) logs exactly the finished trials that have no run yet.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from ..sweep import tracking

EXPERIMENT = "hparams_search"
"""One MLflow experiment holds every study; each study is a parent run in it."""
STUDY_TAG = "tuning_study"
TRIAL_TAG = "tuning_trial"


def study_key(learner: str, scale: str) -> str:
    return f"tuning/{learner}/{scale}"


def prepare_study_run(settings: tracking.TrackingSettings, key: str, tags: dict[str, str]) -> str:
    """Create the store, the experiment and the study's parent run if missing; its run id.

    Called once before the workers start: SQLite stores must not be initialised concurrently.
    """
    client = settings.client()
    experiment_id = tracking.prepare(settings, EXPERIMENT)
    found = _runs(client, experiment_id, f"tags.run_key_hash = '{tracking.key_hash(key)}'")
    if found:
        return found[0].info.run_id
    run = client.create_run(experiment_id, run_name=key, tags={
        **tags, STUDY_TAG: key, "run_key": key, "run_key_hash": tracking.key_hash(key)})
    client.set_terminated(run.info.run_id, "FINISHED")
    return run.info.run_id


def logged_trials(settings: tracking.TrackingSettings, parent_id: str) -> set[int]:
    client = settings.client()
    experiment_id = client.get_run(parent_id).info.experiment_id
    runs = _runs(client, experiment_id, f"tags.mlflow.parentRunId = '{parent_id}'")
    return {int(r.data.tags[TRIAL_TAG]) for r in runs if r.info.status == "FINISHED" and TRIAL_TAG in r.data.tags}


def log_trials(settings: tracking.TrackingSettings, parent_id: str, key: str, trials: Iterable) -> int:
    """Log each finished Optuna trial in ``trials`` that has no run under ``parent_id`` yet."""
    done = logged_trials(settings, parent_id)
    count = 0
    for trial in trials:
        if trial.number not in done and trial.value is not None:
            log_trial(settings, parent_id, key, trial)
            count += 1
    return count


def log_trial(settings: tracking.TrackingSettings, parent_id: str, key: str, trial) -> str:
    from mlflow.entities import Metric, Param

    client = settings.client()
    parent = client.get_run(parent_id)
    record: dict[str, Any] = trial.user_attrs
    role = record.get("role", "random")
    stop = record.get("stopped_early")
    tags = {"mlflow.parentRunId": parent_id, STUDY_TAG: key, TRIAL_TAG: str(trial.number), "role": role}
    if stop is not None:
        tags["stopped_early"] = f"at seed {stop['seed']}, step {stop['step']}"
    run = client.create_run(parent.info.experiment_id, run_name=f"trial {trial.number} ({role})", tags=tags)
    metrics = [Metric("reward_loss" if stop is None else "reward_loss_lower_bound", float(trial.value), 0, 0)]
    seeds = record.get("seeds", [])  # a trial stopped early: the seeds it finished
    if stop is None:  # the mean curve over the tuning seeds exists only when all ran
        metrics += [Metric("mean_reward", float(r), 0, int(s)) for s, r in zip(record["steps"], record["mean_curve"])]
    for name in ("reward_loss", "first_target_reward_step", "first_threshold_step", "learning_span",
                 "time_to_threshold", "final_reward"):
        metrics += [Metric(f"{name}.seed_{seed}", float(v), 0, 0)
                    for seed, v in zip(seeds, record.get(name, [])) if v is not None]
    params = [Param(k, str(v)) for k, v in trial.params.items()]
    params.append(Param("seeds", ",".join(str(s) for s in seeds)))
    if "steps" in record:
        params.append(Param("budget", str(record["steps"][-1])))
    client.log_batch(run.info.run_id, metrics=metrics, params=params)
    client.set_terminated(run.info.run_id, "FINISHED")  # last: an interrupted run is not FINISHED
    return run.info.run_id


def log_study_progress(settings: tracking.TrackingSettings, parent_id: str, finished: int,
                       best: float, defaults: float | None) -> None:
    """The study's best objective so far, step = number of finished trials."""
    from mlflow.entities import Metric

    metrics = [Metric("best_reward_loss", float(best), 0, finished)]
    if defaults is not None:
        metrics.append(Metric("defaults_reward_loss", float(defaults), 0, 0))
    settings.client().log_batch(parent_id, metrics=metrics)


def _runs(client, experiment_id: str, filter_string: str) -> list:
    from mlflow.entities import ViewType

    runs, token = [], None
    while True:
        page = client.search_runs([experiment_id], filter_string, ViewType.ACTIVE_ONLY,
                                  max_results=1000, page_token=token)
        runs += list(page)
        token = page.token
        if not token:
            return runs
