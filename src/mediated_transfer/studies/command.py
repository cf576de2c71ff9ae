"""The command line every study's ``__main__`` shares: help, its own options beside Hydra's
overrides, and a mistake in the command (or missing runs) said in one line, not a traceback."""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence

from ..reporting.compose import USER_ERRORS, one_line
from .shape import Study, build


def command(make: Callable[[list[str]], Study | None], doc: str | None = None,
            errors: tuple[type[BaseException], ...] = USER_ERRORS) -> Callable[[Sequence[str] | None], int]:
    """A ``main(argv)`` that builds the study ``make(args)`` gives (None: ``make`` did the
    command's work itself, e.g. printed a rule's pick). ``doc``: printed for -h / --help (None:
    ``make`` parses its own, with argparse)."""
    def main(argv: Sequence[str] | None = None) -> int:
        args = sys.argv[1:] if argv is None else list(argv)
        if doc is not None and any(a in ("-h", "--help") for a in args):
            print(doc)
            return 0
        try:
            study = make(args)
            if study is not None:
                build(study)
        except errors as error:
            raise SystemExit(f"error: {one_line(error)}") from None
        return 0
    return main


def split_options(args: Sequence[str], options: Sequence[str]) -> tuple[dict[str, str], list[str]]:
    """``args`` as the study's own options (``--name=value``, or ``--flag``: value '') and the
    Hydra overrides; ValueError on an option it does not take."""
    chosen, overrides = {}, []
    for arg in args:
        name, _, value = arg.partition("=")
        if name in options:
            chosen[name] = value
        elif arg.startswith("--"):
            raise ValueError(f"unknown option {name}; allowed: {', '.join(options)}")
        else:
            overrides.append(arg)
    return chosen, overrides
