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
from .compose import USER_ERRORS, ReportError, compose_experiment, experiment_names, one_line, split_experiments

USAGE = __doc__


def build(overrides: Sequence[str]) -> tuple[list[Report], list[str]]:
    """Reports of the named experiments (an error if one has no runs yet), or of every
    experiment that has runs when none is named (an error only if none has); and one line per
    experiment skipped: no runs, or the overrides do not apply to it (algorithm.lambda_ is not
    a key of the DQN experiment)."""
    named, rest = split_experiments(overrides)
    names = named or experiment_names()
    reports, skipped = [], []
    for name in names:
        try:
            reports.append(build_report(compose_experiment(name, rest)))
        except (NoRuns, ReportError) as error:
            if named:
                raise
            skipped.append((name, error))
    if not reports:
        first_name, first = skipped[0]
        if not any(isinstance(error, NoRuns) for _, error in skipped):
            raise first  # the overrides compose for no experiment (e.g. scale=smok): one error says it
        raise NoRuns(f"none of {', '.join(names)} has runs; {first_name}: {first}")
    return reports, [f"{name}: {error}" for name, error in skipped]


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
        for line in report.left_out:
            print(f"  left out: {line}", file=sys.stderr)
        if report.stale:
            print(f"  stale, computed by other code than the current: {'; '.join(report.stale[:3])}"
                  f"{' ...' if len(report.stale) > 3 else ''}; recompute them: rerun the sweep with "
                  "rerun_stale=true", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
