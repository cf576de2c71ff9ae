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

from ..reporting.compose import USER_ERRORS, one_line
from .report import collect, dqn_cells, write_report
from .study import DQN_EXPERIMENT, NONE, SCAFFOLDED, Study, load_first_study, load_study
from .superseded import superseded_section


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


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    if any(a in ("-h", "--help") for a in args):
        print(__doc__)
        return 0
    try:
        unknown = [a for a in args if a.startswith("--") and a != "--dqn-cells"]
        if unknown:
            raise ValueError(f"unknown option {unknown[0]}; this command takes --dqn-cells and Hydra overrides")
        overrides = [a for a in args if a != "--dqn-cells"]
        study = load_study(overrides)
        if "--dqn-cells" in args:
            print(",".join(dqn_cells(study)))
            return 0
        first = load_first_study(overrides)
        superseded = superseded_section(first, collect(first)[0], float(first.config.threshold))
        paths = write_report(study, Path(study.config.paths.reports_dir), superseded, dqn_study(study, overrides),
                             progress=lambda line: print(line, file=sys.stderr))
    except USER_ERRORS as error:
        raise SystemExit(f"error: {one_line(error)}") from None
    print("curricula: " + ", ".join(map(str, paths)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
