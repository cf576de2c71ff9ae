"""``python -m mediated_transfer.tuning LEARNER``: run (or resume) the learner's random search.

    python -m mediated_transfer.tuning rbf --workers 1            # conf/hparams_search, paper scale
    python -m mediated_transfer.tuning rbf --scale smoke --trials 2 --root /tmp/t
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from ..sweep import tracking
from ..config.compose import compose_config
from .space import SearchSpaceError, available_learners, find_search_space
from .study import StudyMismatchError, StudyPlan, run_study, study_folder


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.tuning", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("learner", help="a learner with a search space: " + ", ".join(available_learners()))
    parser.add_argument("--workers", type=int, default=1, help="worker processes (one core each)")
    parser.add_argument("--scale", default=None, help="conf/scale option (default: the search space's)")
    parser.add_argument("--trials", type=int, default=None, help="trial count (default: the search space's)")
    parser.add_argument("--root", type=Path, default=Path("."), help="project root: tuning/, mlflow.db")
    parser.add_argument("--tracking", default="sqlite",
                        help="conf/tracking option for the trials' MLflow runs: sqlite (<root>/mlflow.db), "
                             "server (with --tracking-uri) or none")
    parser.add_argument("--tracking-uri", default=None, help="tracking.uri, for --tracking server")
    return parser.parse_args(argv)


def tracking_settings(args: argparse.Namespace) -> tracking.TrackingSettings | None:
    """The MLflow store of the project's runs, as conf/tracking and conf/paths define it."""
    overrides = [f"tracking={args.tracking}", f"paths.root={args.root.resolve()}"]
    if args.tracking_uri is not None:
        overrides.append(f"tracking.uri={args.tracking_uri}")
    try:
        cfg = compose_config(overrides)
        return tracking.TrackingSettings.from_config(cfg.tracking) if cfg.tracking.enabled else None
    except Exception as error:  # a Hydra composition error or a missing uri: one line
        raise SearchSpaceError(f"--tracking {args.tracking}: {str(error).splitlines()[0]}") from None


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        if args.workers < 1:
            raise SearchSpaceError(f"--workers must be >= 1, got {args.workers}")
        if args.trials is not None and args.trials < 1:
            raise SearchSpaceError(f"--trials must be >= 1, got {args.trials}")
        space = find_search_space(args.learner).with_scale(args.scale)
        plan = StudyPlan(space, study_folder(args.root, space), args.trials or space.trials,
                         args.workers, tracking_settings(args))
        run_study(plan)
    except (SearchSpaceError, StudyMismatchError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
