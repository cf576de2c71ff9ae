"""trials.csv: one row per finished trial, the data behind Table I (committed with the study).

Columns: ``trial``, ``role`` (defaults or random), ``objective`` (mean L_R over the tuning
seeds), ``stopped_early`` (true: the trial was stopped once it could not beat the best, and
``objective`` is a lower bound of its mean L_R; ``stopped_at``: ``<seed>@<step>``), one column
per searched key, per-seed diagnostics ``<name>.seed_<k>`` (reward_loss,
first_target_reward_step, first_threshold_step, learning_span, time_to_threshold, final_reward;
empty: never within the budget, or a seed a stopped trial did not finish), ``duration_s`` and
the mean curve ``mean_reward@<step>`` (trials run to the end).
Also: a consistent copy of a study's SQLite database while workers keep writing to it.
(export.py is their command line.)
"""

from __future__ import annotations

import sqlite3
from contextlib import closing
from pathlib import Path

import pandas as pd

from ..atomic import atomic_write_text

TRIALS_FILE = "trials.csv"
STUDY_FILE = "study.db"
PER_SEED = ("reward_loss", "first_target_reward_step", "first_threshold_step", "learning_span",
            "time_to_threshold", "final_reward")
STEP_COLUMNS = ("first_target_reward_step", "first_threshold_step", "learning_span", "time_to_threshold")


def trials_frame(study) -> pd.DataFrame:
    from optuna.trial import TrialState

    rows = []
    for trial in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE, TrialState.PRUNED)):
        record = trial.user_attrs
        stop = record.get("stopped_early")
        row = {"trial": trial.number, "role": record.get("role", "random"), "objective": trial.value,
               "stopped_early": stop is not None,
               "stopped_at": None if stop is None else f"{stop['seed']}@{stop['step']}"}
        row.update(trial.params)
        for name in PER_SEED:
            row.update({f"{name}.seed_{s}": v for s, v in zip(record.get("seeds", []), record.get(name, []))})
        duration = trial.datetime_complete - trial.datetime_start
        row["duration_s"] = round(duration.total_seconds(), 1)
        if stop is None:
            row.update({f"mean_reward@{s}": r for s, r in zip(record["steps"], record["mean_curve"])})
        rows.append(row)
    frame = pd.DataFrame(rows)
    for column in frame.columns:
        if column.split(".seed_")[0] in STEP_COLUMNS:
            frame[column] = frame[column].astype("Int64")  # steps stay integers, never 1.2e5
    return frame.sort_values("trial").reset_index(drop=True) if rows else frame


def write_trials_csv(study, folder: Path) -> Path:
    path = Path(folder) / TRIALS_FILE
    atomic_write_text(path, trials_frame(study).to_csv(index=False, float_format="%.6g"))
    return path


def backup_database(source: Path, target: Path) -> Path:
    """A consistent copy of the SQLite file ``source`` (SQLite's online backup), e.g. to commit."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    with closing(sqlite3.connect(source)) as src, closing(sqlite3.connect(target)) as dst:
        src.backup(dst)
    return target
