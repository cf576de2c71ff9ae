"""``python -m mediated_transfer.tuning.export LEARNER [--snapshot DIR]``: a study's trials.csv
(trials.py) rewritten from its database, or a consistent copy of both to commit while workers
keep writing (make tune-snapshot)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from .space import SearchSpaceError, find_search_space
from .study import StudyPlan, load_study, study_folder
from .trials import STUDY_FILE, backup_database, write_trials_csv


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m mediated_transfer.tuning.export LEARNER [--snapshot DIR]``: rewrite trials.csv
    from the study (running or not); with --snapshot, write a consistent pair instead: a copy
    of study.db and the trials.csv of that copy, in DIR (to commit while workers keep going)."""
    import optuna

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
