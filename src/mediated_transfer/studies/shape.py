"""A study's shape and the one driver that builds its report.

A study is its registration (where the rules it decides by were fixed before its runs), the
stored runs it reads, what it measures from them, and the report those measures give. The steps
are plain functions, so each study keeps its own types between them; the driver runs them in
order, judges the runs' staleness through provenance/judge.py, writes the report's texts
atomically and says what it wrote.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Generic, TypeVar

from ..atomic import atomic_write_text
from ..provenance.judge import stale
from ..results import RunResult

Runs = TypeVar("Runs")
Measures = TypeVar("Measures")


@dataclass
class Written:
    """What a study's report step hands the driver."""

    texts: dict[Path, str]
    """The report's text files, written by the driver atomically, in this order: a reader never
    sees half a report."""
    files: list[Path] = field(default_factory=list)
    """Files the report step wrote itself (figures, CSV tables): listed, not rewritten."""

    @property
    def paths(self) -> list[Path]:
        return [*self.texts, *self.files]


def _no_results(runs: object) -> Iterable[RunResult]:
    return ()


@dataclass(frozen=True)
class Study(Generic[Runs, Measures]):
    name: str
    """How the study's command names it in what it prints."""
    registration: str
    """Where its registered rules and measures live (a conf/ file, a module): read before its runs."""
    runs: Callable[[], Runs]
    """The stored runs it reads (result.json files, trials.csv)."""
    measures: Callable[[Runs], Measures]
    """Its numbers, from those runs alone."""
    report: Callable[[Measures], Written]
    """Markdown and figures from the measures: draws its figures, returns its texts."""
    results: Callable[[Runs], Iterable[RunResult]] = _no_results
    """Every run result among ``runs``, for the staleness check (none: the study reads no runs)."""


def stale_runs(results: Iterable[RunResult]) -> list[str]:
    """One line per run computed by other code than the current (the one judge,
    provenance/judge.py)."""
    lines = []
    for r in results:
        try:
            why = stale(r)
        except (KeyError, TypeError, ValueError) as error:
            # A record the judge cannot read (hand-made, or an old format) is named, not fatal: the
            # report is still built, as the tables' is from stale runs.
            why = f"its record cannot be judged ({type(error).__name__}: {error})"
        if why is not None:
            lines.append(f"{r.strategy}_{r.n_source} seed={r.seed}: {why}")
    return lines


def build(study: Study, say: Callable[[str], None] = print) -> list[Path]:
    """Run ``study``'s steps, write its report and say what was written (one line); stale runs
    are named on stderr: the report is built from them all the same, as the tables' is."""
    runs = study.runs()
    old = stale_runs(study.results(runs))
    written = study.report(study.measures(runs))
    for path, text in written.texts.items():
        atomic_write_text(path, text)
    say(f"{study.name}: " + ", ".join(map(str, written.paths)))
    if old:
        print(f"  {len(old)} stale, computed by other code than the current: {'; '.join(old[:3])}"
              f"{' ...' if len(old) > 3 else ''}", file=sys.stderr)
    return written.paths
