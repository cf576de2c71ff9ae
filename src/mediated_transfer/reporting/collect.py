"""Read the finished runs of a sweep, grouped by table cell: the input of every table and figure.

A table sweep leaves ``<sweep_dir>/<cell>/seed=<k>/result.json`` per finished run of the baseline
and ``<sweep_dir>/<cell>/seed=<k>/<variant>/result.json`` per finished run of a variant, where
the variant is Hydra's override_dirname of the run (its overrides besides table cell, seed, scale
and locations; conf/config.yaml: hydra.sweep.subdir). A report reads one variant only, so the
baseline and its variants never mix. Unfinished runs have no result.json and are not there yet.
A run the judge sets aside (provenance/judge.py: a damaged run, or another cell's or seed's run
moved or copied into a folder) is left out and named, one line each: tables are built from the
runs that can be trusted, and say how many were left out.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..metrics import MetricsConfig, summarise_runs
from ..provenance.judge import judge
from ..results import RESULT_FILE, RunResult

BASELINE = ""
"""The variant of a sweep run with no overrides beyond table cell, seed and locations."""


def variant_label(variant: str) -> str:
    return variant or "baseline"


@dataclass
class CellRuns:
    """The finished runs of one table cell (strategy and N_source)."""

    strategy: str
    n_source: int
    results: list[RunResult] = field(default_factory=list)
    """The runs that ran their budget: the cell's statistics are theirs."""
    failed: list[RunResult] = field(default_factory=list)
    """Runs stopped as failed (a diverged learner): counted and named, not averaged."""

    @property
    def cell(self) -> str:
        return f"{self.strategy}_{self.n_source}"

    @property
    def seeds(self) -> list[int]:
        return sorted(r.seed for r in self.results)

    def summary(self, config: MetricsConfig) -> dict:
        """metrics.summarise_runs of the cell's curves (mean and SEM curves, L_R, time to
        threshold) over the runs that ran their budget (there must be one)."""
        steps = self.results[0].steps
        return summarise_runs(np.array([r.mean_reward for r in self.results]), steps, config)


def summaries(cells: dict[str, CellRuns], config: MetricsConfig) -> dict[str, dict]:
    """The summary of every cell that has a run which ran its budget."""
    return {name: c.summary(config) for name, c in cells.items() if c.results}


def collect_sweep(sweep_dir: str | Path, algorithm: str | None = None,
                  representation: str | None = None, budget: int | None = None,
                  eval_points: int | None = None, variant: str = BASELINE,
                  eval_episodes: int | None = None, left_out: list[str] | None = None) -> dict[str, CellRuns]:
    """The finished runs of ``variant`` under ``sweep_dir`` by cell name, runs sorted by seed.

    A damaged run, or another cell's or seed's run in a folder (moved or copied there), is left
    out: its line (the file, what is wrong) goes into ``left_out``, or, without that list, to
    stderr.

    With ``algorithm``/``representation``/``budget``/``eval_points``/``eval_episodes`` given, a
    run of another learner, budget or evaluation schedule in the folder is an error (it would
    silently mix into the table, whose header states the schedule, otherwise); so is a run whose
    curve has other evaluation steps than the rest of its cell.
    """
    sweep_dir = Path(sweep_dir)
    cells: dict[str, CellRuns] = {}
    for seed_dir in sorted(sweep_dir.glob("*/seed=*")):
        folder = seed_dir / variant
        verdict = judge(folder, place=(seed_dir.parent.name, seed_dir.name.removeprefix("seed=")))
        if verdict.damaged is not None:  # set aside by a sweep, left out by a report
            if left_out is None:
                print(f"left out: {verdict.damaged}", file=sys.stderr)
            else:
                left_out.append(str(verdict.damaged))
            continue
        result = verdict.result
        if result is None:  # not finished (yet)
            continue
        expected = {"algorithm": algorithm, "representation": representation, "budget": budget}
        for key, wanted in expected.items():
            if wanted is not None and getattr(result, key) != wanted:
                raise ValueError(f"{folder}: {key}={getattr(result, key)!r}, but this table expects "
                                 f"{key}={wanted!r}; the folder belongs to another sweep")
        recorded = (result.config.get("scale") or {}).get("eval_episodes")  # older results: none
        if eval_episodes is not None and recorded is not None and int(recorded) != eval_episodes:
            raise ValueError(f"{folder}: evaluated on {recorded} episodes per point, but this table "
                             f"states scale.eval_episodes={eval_episodes}; report with "
                             f"scale.eval_episodes={recorded}, or rerun the sweep")
        if eval_points is not None and len(result.steps) != eval_points and not result.failed:
            raise ValueError(f"{folder}: {len(result.steps)} evaluation points, but this table "
                             f"expects eval_points={eval_points}; the folder belongs to another sweep")
        cell_name = f"{result.strategy}_{result.n_source}"
        cell = cells.setdefault(cell_name, CellRuns(result.strategy, result.n_source))
        if result.failed:  # its curve stops where the run was stopped
            cell.failed.append(result)
            continue
        if cell.results and cell.results[0].steps != result.steps:
            raise ValueError(f"{folder}: evaluation steps differ from the other runs of {cell_name} "
                             f"({result.steps[:3]}... vs {cell.results[0].steps[:3]}...)")
        cell.results.append(result)
    for cell in cells.values():
        cell.results.sort(key=lambda r: r.seed)
        cell.failed.sort(key=lambda r: r.seed)
    return cells


def runs_per_variant(sweep_dir: str | Path) -> dict[str, int]:
    """How many finished runs each variant (baseline: '') has under ``sweep_dir``, baseline first."""
    sweep_dir = Path(sweep_dir)
    counts: dict[str, int] = {}
    for path in sweep_dir.glob(f"*/seed=*/**/{RESULT_FILE}"):
        variant = "/".join(path.relative_to(sweep_dir).parts[2:-1])
        counts[variant] = counts.get(variant, 0) + 1
    return dict(sorted(counts.items()))
