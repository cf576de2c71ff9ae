"""The command: load the runs, decide the claims once, write REPRODUCTION.md and, beside it, the
README's headline."""

from __future__ import annotations

import argparse
from pathlib import Path

from .claims import evaluate
from .document import render
from .headline import headline, with_headline
from .runs import load


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.reporting.reproduction",
                                     description="reports/REPRODUCTION.md, a verdict on each of the paper's six "
                                     "headline claims from the committed paper-scale runs of Tables II-IV, and "
                                     "the README's headline beside it.")
    parser.add_argument("--root", default=".", help="the checkout whose multirun/ holds the runs")
    parser.add_argument("--out", default=None, help="where to write (default: <root>/reports/REPRODUCTION.md)")
    args = parser.parse_args(argv)
    root = Path(args.root)
    learners = load(root)
    if not any(lr.cells for lr in learners.values()):
        raise SystemExit(f"no paper-scale runs under {root / 'multirun'}: run make reproduce-tables first")
    out = Path(args.out) if args.out else root / "reports" / "REPRODUCTION.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    claims = evaluate(learners)
    out.write_text(render(learners, claims))
    print(f"wrote {out}")
    readme = root / "README.md"
    if args.out is None and readme.is_file():  # the headline of the README beside the report
        readme.write_text(with_headline(readme.read_text(), headline(learners, claims)))
        print(f"wrote the headline of {readme}")
    return 0
