"""trials.csv: one row per finished trial, the data behind Table I (committed with the study).

Columns: ``trial``, ``role`` (defaults or random), ``objective`` (mean L_R over the tuning
seeds), one column per searched key, per-seed diagnostics ``<name>.seed_<k>`` (reward_loss,
first_target_reward_step, first_threshold_step, learning_span, time_to_threshold, final_reward;
empty: never within the budget), ``duration_s`` and the mean curve ``mean_reward@<step>``.
Also: a consistent copy of a study's SQLite database while workers keep writing to it.
"""

from __future__ import annotations

import sqlite3
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
    for trial in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)):
        record = trial.user_attrs
        row = {"trial": trial.number, "role": record.get("role", "random"), "objective": trial.value}
        row.update(trial.params)
        for name in PER_SEED:
            row.update({f"{name}.seed_{s}": v for s, v in zip(record["seeds"], record[name])})
        duration = trial.datetime_complete - trial.datetime_start
        row["duration_s"] = round(duration.total_seconds(), 1)
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
    with sqlite3.connect(source) as src, sqlite3.connect(target) as dst:
        src.backup(dst)
    return target
