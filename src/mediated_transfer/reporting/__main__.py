"""``python -m mediated_transfer.reporting [experiment=table2_rbf,...] [scale=quick] [overrides]``

Builds the tables and figures of the given experiments (default: every experiment in
conf/experiment/ that has runs) from the outputs of their sweeps. Overrides are the ones the
sweep was run with (scale, paths.root, tracking, ...), so that the same config locates the same
outputs; overrides that change what a run computes (e.g. algorithm.lambda_=0.5) name a variant,
whose runs alone are reported, into <paths.reports_dir>/variants/<variant>/.
Compare sweeps side by side with python -m mediated_transfer.reporting.compare.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from .build import NoRuns, Report, build_report
from .compose import USER_ERRORS, compose_experiment, experiment_names, one_line, split_experiments

USAGE = __doc__


def build(overrides: Sequence[str]) -> tuple[list[Report], list[str]]:
    """Reports of the named experiments (an error if one has no runs yet), or of every
    experiment that has runs when none is named (an error only if none has); and one line per
    experiment skipped for want of runs."""
    named, rest = split_experiments(overrides)
    reports, skipped = [], []
    names = named or experiment_names()
    for name in names:
        cfg = compose_experiment(name, rest)
        try:
            reports.append(build_report(cfg))
        except NoRuns as error:
            if named:
                raise
            skipped.append(str(error))
    if not reports:
        raise NoRuns(f"none of {', '.join(names)} has runs; {names[0]}: {skipped[0]}")
    return reports, skipped


def main(argv: Sequence[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    if any(a in ("-h", "--help") for a in args):
        print(USAGE)
        return 0
    try:
        reports, skipped = build(args)
    except USER_ERRORS as error:
        raise SystemExit(f"error: {one_line(error)}") from None
    for message in skipped:
        print(f"skipped: {message}", file=sys.stderr)
    for report in reports:
        print(report.line())
    return 0


if __name__ == "__main__":
    sys.exit(main())
