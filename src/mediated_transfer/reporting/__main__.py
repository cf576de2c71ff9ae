"""``python -m mediated_transfer.reporting [experiment=table2_rbf,...] [scale=quick] [overrides]``

Builds the tables and figures of the given experiments (default: every experiment in
conf/experiment/) from the outputs of their sweeps. Overrides are the ones the sweep was run
with (scale, paths.root, tracking, ...), so that the same config locates the same outputs.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Sequence

from ..config.compose import CONF_DIR, CONFIG_NAME, prepare_overrides as quote_numeric_choices
from .build import Report, build_report

USAGE = __doc__


def experiments_of(overrides: Sequence[str]) -> tuple[list[str], list[str]]:
    """(experiment names, the other overrides); all of conf/experiment/ when none is named."""
    names, rest = [], []
    for arg in overrides:
        if arg.startswith("experiment="):
            names += [n for n in arg.split("=", 1)[1].split(",") if n]
        else:
            rest.append(arg)
    available = sorted(p.stem for p in (CONF_DIR / "experiment").glob("*.yaml"))
    unknown = sorted(set(names) - set(available))
    if unknown:
        raise SystemExit(f"unknown experiment {', '.join(unknown)}; allowed: {', '.join(available)}")
    return names or available, rest


def build(overrides: Sequence[str]) -> list[Report]:
    """Reports of the named experiments (an error if one has no runs yet), or of every
    experiment that has runs when none is named (an error only if none has)."""
    from hydra import compose, initialize_config_dir

    named = any(a.startswith("experiment=") for a in overrides)
    names, rest = experiments_of(overrides)
    reports, missing = [], []
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        for name in names:
            cfg = compose(CONFIG_NAME, overrides=[f"experiment={name}", *quote_numeric_choices(rest)])
            try:
                reports.append(build_report(cfg))
            except FileNotFoundError as error:
                if named:
                    raise
                missing.append(str(error))
    if not reports:
        raise FileNotFoundError("\n".join(missing))
    for message in missing:
        print(f"skipped: {message}", file=sys.stderr)
    return reports


def main(argv: Sequence[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    if any(a in ("-h", "--help") for a in args):
        print(USAGE)
        return 0
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    try:
        reports = build(args)
    except (FileNotFoundError, ValueError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    for report in reports:
        files = [*map(str, report.tables), *([str(report.figure)] if report.figure else [])]
        print(f"{report.name}: {report.runs} runs -> {', '.join(files)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
