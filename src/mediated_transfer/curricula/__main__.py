"""``python -m mediated_transfer.curricula [overrides]``: reports/CURRICULA.md, its tables
(reports/curricula/curricula_<learner>_<world>*.csv) and figures, from the runs of
``python -m mediated_transfer experiment=curricula2 'hydra.searchpath=[pkg://auto_curricula.conf]'``
with the same overrides (scale, paths.root, and e.g. hydra.sweeper.params.seed=4000,
representation=fsr or env=default for a smaller check), and the first study's superseded
numbers from its committed runs. `make curricula` runs the sweep and this.

``--dqn-cells`` prints the cells of the DQN's sweep that the registered rule picks
(`make curricula-dqn` runs it)."""

from __future__ import annotations

import sys
from pathlib import Path

from ..studies import Study as StudyShape
from ..studies import command, split_options
from .report import dqn_cells, measure, report
from .study import DQN_EXPERIMENT, NONE, SCAFFOLDED, Study, StudyRuns, collect, load_first_study, load_study


def dqn_study(study: Study, overrides: list[str]) -> Study:
    """The DQN's arms: its file's cells and, once the linear runs pick them, the two curricula."""
    kept = [o for o in overrides if o.startswith(("scale=", "paths.", "tracking=", "hydra.searchpath",
                                                  "hydra.sweeper.params.seed"))]
    dqn = load_study(kept, DQN_EXPERIMENT, (NONE, SCAFFOLDED))
    try:
        cells = tuple(dict.fromkeys(dqn.cells + tuple(dqn_cells(study))))
    except ValueError:  # not picked yet
        cells = dqn.cells
    return Study(dqn.experiment, dqn.groups, cells, dqn.seeds)


def curricula(args: list[str]) -> StudyShape | None:
    """The study as a registration -> runs -> measures -> report (studies/shape.py); None after
    --dqn-cells, which only prints the rule's pick."""
    options, overrides = split_options(args, ("--dqn-cells",))
    study = load_study(overrides)
    if "--dqn-cells" in options:
        print(",".join(dqn_cells(study)))
        return None
    first, dqn = load_first_study(overrides), dqn_study(study, overrides)
    return StudyShape(
        "curricula", str(study.registration), lambda: StudyRuns(collect(study), collect(dqn), collect(first)),
        lambda runs: measure(study, runs, dqn, first, progress=lambda line: print(line, file=sys.stderr)),
        lambda measured: report(study, measured, Path(study.config.paths.reports_dir)), StudyRuns.results)


main = command(curricula, __doc__)

if __name__ == "__main__":
    sys.exit(main())
