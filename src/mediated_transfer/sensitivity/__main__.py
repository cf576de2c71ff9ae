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
from ..studies import Study, command, split_options
from .measures import Measures
from .report import collect, measure, report
from .study import EXPERIMENT, load_study

OPTIONS = {"--random-episodes": "random_episodes", "--resamples": "resamples"}


def sensitivity(args: list[str]) -> Study:
    """The study as a registration -> runs -> measures -> report (studies/shape.py)."""
    options, overrides = split_options(args, OPTIONS)
    measures = Measures()
    for name, value in options.items():
        if not value.isdigit() or int(value) < 1:
            raise ValueError(f"{name} must be a positive integer, got {value!r}")
        measures = replace(measures, **{OPTIONS[name]: int(value)})
    study = load_study(overrides)
    # A variant's report goes to variants/<variant>/, as the tables' do: it never overwrites
    # the study's own.
    out = reports_dir(study.config, study.variant)
    return Study(
        "sensitivity", f"conf/experiment/{EXPERIMENT}.yaml", lambda: collect(study),
        lambda runs: measure(study, runs, measures, progress=lambda line: print(line, file=sys.stderr)),
        lambda results: report(study, results, measures, out),
        lambda runs: [r for cells in runs.values() for c in cells.values() for r in (*c.results, *c.failed)])


main = command(sensitivity, __doc__)

if __name__ == "__main__":
    sys.exit(main())
