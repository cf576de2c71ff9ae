"""``python -m mediated_transfer.sensitivity [--random-episodes N] [--resamples N] [overrides]``

Builds reports/SENSITIVITY.md, its table (reports/sensitivity/sensitivity.csv) and figure from
the runs of ``python -m mediated_transfer experiment=sensitivity`` with the same overrides
(scale, paths.root, and e.g. env=default,tool_frame seed=0 for a smaller check). With other
learner values (tuned=linear_q_rbf_round1, algorithm.lambda_=0.5) the report is that variant's,
in reports/variants/<variant>/. The options
change the study's measures from their pre-registered values (sensitivity/measures.py), for
quick checks only."""

from __future__ import annotations

import sys
from dataclasses import replace

from ..reporting.build import reports_dir
from ..reporting.compose import USER_ERRORS, one_line
from .measures import Measures
from .report import write_report
from .study import load_study

OPTIONS = {"--random-episodes": "random_episodes", "--resamples": "resamples"}


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    if any(a in ("-h", "--help") for a in args):
        print(__doc__)
        return 0
    measures, overrides = Measures(), []
    try:
        for arg in args:
            name, _, value = arg.partition("=")
            if name in OPTIONS:
                if not value.isdigit() or int(value) < 1:
                    raise ValueError(f"{name} must be a positive integer, got {value!r}")
                measures = replace(measures, **{OPTIONS[name]: int(value)})
            elif arg.startswith("--"):
                raise ValueError(f"unknown option {name}; allowed: {', '.join(OPTIONS)}")
            else:
                overrides.append(arg)
        study = load_study(overrides)
        # A variant's report goes to variants/<variant>/, as the tables' do: it never overwrites
        # the study's own.
        paths = write_report(study, measures, reports_dir(study.config, study.variant),
                             progress=lambda line: print(line, file=sys.stderr))
    except USER_ERRORS as error:
        raise SystemExit(f"error: {one_line(error)}") from None
    print("sensitivity: " + ", ".join(map(str, paths)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
