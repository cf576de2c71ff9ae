"""``python -m mediated_transfer.curricula [overrides]``: reports/CURRICULA.md, its tables
(reports/curricula/curricula_<learner>.csv) and figures, from the runs of
``python -m mediated_transfer experiment=curricula representation=<rbf|fsr>
'hydra.searchpath=[pkg://auto_curricula.conf]'`` with the same overrides (scale, paths.root,
and e.g. hydra.sweeper.params.seed=3000 or representation=fsr for a smaller check). `make
curricula` runs the sweeps and this."""

from __future__ import annotations

import sys
from pathlib import Path

from ..reporting.compose import USER_ERRORS, one_line
from .report import write_report
from .study import load_study


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    if any(a in ("-h", "--help") for a in args):
        print(__doc__)
        return 0
    try:
        unknown = [a for a in args if a.startswith("--")]
        if unknown:
            raise ValueError(f"unknown option {unknown[0]}; this command takes only Hydra overrides")
        study = load_study(args)
        paths = write_report(study, Path(study.config.paths.reports_dir),
                             progress=lambda line: print(line, file=sys.stderr))
    except USER_ERRORS as error:
        raise SystemExit(f"error: {one_line(error)}") from None
    print("curricula: " + ", ".join(map(str, paths)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
