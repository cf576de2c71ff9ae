"""The committed paper-scale runs of Tables II-IV, per learner, beside the paper's rows: what every
claim and table of the report is read from."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...metrics import MetricsConfig, first_point_at_threshold
from ...provenance.judge import stale
from ..collect import CellRuns, collect_sweep
from ..intervals import MeanCurveTime, mean_curve_time
from ..paper import paper_rows

TABLES = {"II": ("table2_rbf", "RBF"), "III": ("table3_fsr", "FSR"), "IV": ("table4_dnn", "DNN")}
"""The paper's table -> (our experiment, the learner's name)."""
BUDGET = 500_000
THRESHOLD = MetricsConfig().threshold
MAX_REWARD = MetricsConfig().max_reward
EXPECTED_RUNS = 20
"""Runs per row, as in the paper."""


@dataclass
class Learner:
    """One learner's table: our runs per row (cell: strategy_N_source) and the paper's row."""

    table: str
    name: str
    cells: dict[str, CellRuns]
    paper: dict

    def runs(self, cell: str) -> list:
        return self.cells[cell].results if cell in self.cells else []

    def reward_losses(self, cell: str) -> np.ndarray:
        return np.array([r.reward_loss for r in self.runs(cell)])

    def times_to_threshold(self, cell: str) -> np.ndarray:
        """Per-run time to threshold, +inf for a run that never reaches it (slower than any)."""
        return np.array([math.inf if r.time_to_threshold is None else r.time_to_threshold
                         for r in self.runs(cell)], dtype=float)

    def never_learn(self, cell: str) -> int:
        return sum(map(never_learns, self.runs(cell)))

    def stale(self) -> int:
        """Runs computed by other code than the current (provenance/judge.py): 0 when every
        verdict is today's code's."""
        return sum(bool(stale(r)) for c in self.cells.values() for r in (*c.results, *c.failed))

    def mean_curve_time(self, cell: str) -> int | None:
        """The time to threshold of the row's mean curve: how the paper reads its own."""
        return self.cells[cell].summary(MetricsConfig())["time_to_threshold"]

    def mean_curve_reaching(self, cell: str) -> MeanCurveTime:
        """The mean curve's time to threshold with its bootstrap over the row's runs (R3): over the
        runs that ran their budget, as the mean curve is."""
        runs = self.runs(cell)
        return mean_curve_time([r.mean_reward for r in runs], runs[0].steps, MetricsConfig())

    def paper_time(self, cell: str) -> float:
        """The paper's time to threshold of a row, +inf where it has "-" (never reached)."""
        time = self.paper[cell].time_to_threshold
        return math.inf if time is None else time

    def run_count(self) -> int:
        """Runs of every row, failed ones included."""
        return sum(len(c.results) + len(c.failed) for c in self.cells.values())

    def expected_runs(self) -> int:
        return len(self.paper) * EXPECTED_RUNS


def never_learns(run) -> bool:
    """No evaluation point of the run reaches <R> >= 8."""
    return first_point_at_threshold(run.mean_reward, THRESHOLD) is None


def load(root: Path) -> dict[str, Learner]:
    """Each table's learner, from <root>/multirun/<experiment>/paper (no runs: no cells)."""
    learners = {}
    for table, (experiment, name) in TABLES.items():
        sweep = root / "multirun" / experiment / "paper"
        cells = collect_sweep(sweep, budget=BUDGET) if sweep.is_dir() else {}
        learners[table] = Learner(table, name, cells, {r.cell: r for r in paper_rows(table)})
    return learners
