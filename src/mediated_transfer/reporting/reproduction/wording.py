"""How the report writes its numbers, shared by the claims and the tables: learning steps in
thousands ("80k", "never"), a span of ratios, a row of a part with its interval, a mean curve's
time to threshold with its bootstrap."""

from __future__ import annotations

import math

import numpy as np

from ..intervals import MeanCurveTime, format_interval
from ..verdicts import Row
from .runs import Learner


def steps_k(value: float | None) -> str:
    """Learning steps as the paper writes them, '80k'; 'never' for a time never reached."""
    if value is None or math.isinf(value):
        return "never"
    return f"{value / 1000:.0f}k"


def span(values: list[float]) -> str:
    """The range of some ratios, '0.15-0.31', or one value where they round alike."""
    lo, hi = min(values), max(values)
    return f"{lo:.2f}" if f"{lo:.2f}" == f"{hi:.2f}" else f"{lo:.2f}-{hi:.2f}"


def ratio_row(label: str, paper: str, ours: tuple[float, float, float], prefix: str, outcome: str,
              note: str = "") -> Row:
    """A part's row whose estimate is a ratio with its interval (``prefix``: the numbers it divides)."""
    return Row(label, paper, f"{prefix}{format_interval(ours)}", outcome, note)


def median_times(learner: Learner, a: str, b: str) -> str:
    """Median per-run times to threshold of two rows, as 'a / b: '."""
    return (f"{steps_k(np.median(learner.times_to_threshold(a)))} / "
            f"{steps_k(np.median(learner.times_to_threshold(b)))}: ")


def reaching(evidence: MeanCurveTime) -> str:
    """A mean curve's time to threshold with its interval and the share of resamples that reach
    it (R3), as 'mean curve never [80k, never], reaches in 42.0% of resamples'."""
    point, low, high = evidence.interval
    return (f"mean curve {steps_k(point)} [{steps_k(low)}, {steps_k(high)}], "
            f"reaches in {evidence.share_reaching:.1%} of resamples")


def failed(cell_runs) -> str:
    """'; 1 run failed (not averaged)' where a row has runs stopped as failed, else ''."""
    n = len(cell_runs.failed)
    return f"; {n} run{'s' if n != 1 else ''} failed (not averaged)" if n else ""
