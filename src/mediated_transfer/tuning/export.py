"""trials.csv: one row per finished trial, the data behind Table I (committed with the study).

Columns: ``trial``, ``role`` (defaults or random), ``objective`` (mean L_R over the tuning
seeds), ``stopped_early`` (true: the trial was stopped once it could not beat the best, and
``objective`` is a lower bound of its mean L_R; ``stopped_at``: ``<seed>@<step>``), one column
per searched key, per-seed diagnostics ``<name>.seed_<k>`` (reward_loss,
first_target_reward_step, first_threshold_step, learning_span, time_to_threshold, final_reward;
empty: never within the budget, or a seed a stopped trial did not finish), ``duration_s`` and
the mean curve ``mean_reward@<step>`` (trials run to the end).
Also: a consistent copy of a study's SQLite database while workers keep writing to it.
"""

from __future__ import annotations

import argparse
import sqlite3
import sys
from collections.abc import Sequence
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


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m mediated_transfer.tuning.export LEARNER [--snapshot DIR]``: rewrite trials.csv
    from the study (running or not); with --snapshot, write a consistent pair instead: a copy
    of study.db and the trials.csv of that copy, in DIR (to commit while workers keep going)."""
    import optuna

    from .space import SearchSpaceError, find_search_space
    from .study import StudyPlan, load_study, study_folder

    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.tuning.export")
    parser.add_argument("learner")
    parser.add_argument("--scale", default=None)
    parser.add_argument("--root", type=Path, default=Path("."))
    parser.add_argument("--snapshot", type=Path, default=None, help="folder for the copy of study.db + trials.csv")
    args = parser.parse_args(argv)
    try:
        space = find_search_space(args.learner).with_scale(args.scale)
    except SearchSpaceError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    folder = study_folder(args.root, space)
    if not (folder / STUDY_FILE).is_file():
        print(f"error: no study at {folder / STUDY_FILE}", file=sys.stderr)
        return 2
    if args.snapshot is None:
        print(write_trials_csv(load_study(StudyPlan(space, folder, trials=space.trials)), folder))
        return 0
    copy = backup_database(folder / STUDY_FILE, args.snapshot / STUDY_FILE)
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.load_study(study_name=space.learner, storage=f"sqlite:///{copy}")
    print(copy, write_trials_csv(study, args.snapshot), sep="\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
