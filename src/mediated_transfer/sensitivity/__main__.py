"""``python -m mediated_transfer.sensitivity [scale=...] [overrides]``: reports/SENSITIVITY.md,
its table (reports/sensitivity/sensitivity.csv) and figure from the runs of
``python -m mediated_transfer experiment=sensitivity`` with the same overrides."""

from __future__ import annotations

import sys
from pathlib import Path

from ..reporting.compose import USER_ERRORS, one_line
from .measures import Measures
from .report import write_report
from .study import load_study


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    if any(a in ("-h", "--help") for a in args):
        print(__doc__)
        return 0
    try:
        study = load_study(args)
        paths = write_report(study, Measures(), Path(study.config.paths.reports_dir),
                             progress=lambda line: print(line, file=sys.stderr))
    except USER_ERRORS as error:
        raise SystemExit(f"error: {one_line(error)}") from None
    print("sensitivity: " + ", ".join(map(str, paths)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
