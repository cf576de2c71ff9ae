"""The command: load the runs, decide the claims once, write REPRODUCTION.md and, beside it, the
README's headline."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ...studies import Study, Written, command
from .claim import Claim
from .claims import evaluate
from .document import render
from .headline import headline, with_headline
from .open_question import read as read_open_question
from .runs import Learner, load


def study(argv: list[str]) -> Study:
    """The reproduction as a registration -> runs -> measures -> report (studies/shape.py): its
    registration is each claim's rule, beside the claim (claims/, verdicts.py)."""
    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.reporting.reproduction",
                                     description="reports/REPRODUCTION.md, a verdict on each of the paper's six "
                                     "headline claims from the committed paper-scale runs of Tables II-IV, and "
                                     "the README's headline beside it.")
    parser.add_argument("--root", default=".", help="the checkout whose multirun/ holds the runs")
    parser.add_argument("--out", default=None, help="where to write (default: <root>/reports/REPRODUCTION.md)")
    args = parser.parse_args(argv)
    root = Path(args.root)
    out = Path(args.out) if args.out else root / "reports" / "REPRODUCTION.md"
    readme = root / "README.md"

    def runs() -> dict[str, Learner]:
        learners = load(root)
        if not any(lr.cells for lr in learners.values()):
            raise SystemExit(f"no paper-scale runs under {root / 'multirun'}: run make reproduce-tables first")
        return learners

    def report(measured: tuple[dict[str, Learner], list[Claim]]) -> Written:
        learners, claims = measured
        question = read_open_question(root)  # Table V's answer, or where it stands
        texts = {out: render(learners, claims, question)}
        if args.out is None and readme.is_file():  # the headline of the README beside the report
            texts[readme] = with_headline(readme.read_text(), headline(learners, claims, question))
        return Written(texts)

    return Study("reproduction", "reporting/reproduction/claims/ and reporting/verdicts.py", runs,
                 lambda learners: (learners, evaluate(learners)), report,
                 lambda learners: [r for lr in learners.values() for c in lr.cells.values()
                                   for r in (*c.results, *c.failed)])


main = command(study)

if __name__ == "__main__":
    sys.exit(main())
