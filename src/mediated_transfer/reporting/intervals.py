"""Interval estimates over runs for the reproduction report (rliable-style, Agarwal et al. 2021):
percentile-bootstrap intervals of a ratio of means and of a mean curve's time to threshold, the
interquartile mean, and the probability of improvement. Pure functions of per-run values; resampling is seeded, so a report rebuilds
identically from the same runs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

from ..metrics import MetricsConfig, time_to_threshold, times_to_threshold_of_curves

RESAMPLES = 10_000
CONFIDENCE = 0.95
SEED = 0


def iqm(values: Sequence[float]) -> float:
    """Interquartile mean: the mean of the middle 50 % of the values (robust to a few outliers,
    more efficient than the median)."""
    return float(stats.trim_mean(np.asarray(values, dtype=float), 0.25))


def sem(values: Sequence[float]) -> float:
    """Standard error of the mean (sample std, ddof=1, over sqrt(n)); nan for fewer than 2 runs."""
    a = np.asarray(values, dtype=float)
    return float(a.std(ddof=1) / math.sqrt(a.size)) if a.size > 1 else math.nan


def probability_of_improvement(better: Sequence[float], reference: Sequence[float]) -> float:
    """P(X < Y) + P(X = Y) / 2 for a run X of ``better`` and a run Y of ``reference``, lower
    being better (the Mann-Whitney U statistic over n_x n_y)."""
    x, y = np.asarray(better, dtype=float)[:, None], np.asarray(reference, dtype=float)[None, :]
    return float(((x < y) + 0.5 * (x == y)).mean())


def bootstrap(statistic: Callable[..., float], *groups: Sequence[float], resamples: int = RESAMPLES,
              seed: int = SEED) -> tuple[float, float, float]:
    """(point, low, high): ``statistic(*groups)`` and its percentile-bootstrap interval,
    each group resampled with replacement on its own (runs of different cells are independent).
    Non-finite resampled values (e.g. a ratio over a zero mean) stay in the ranking as +inf."""
    arrays = [np.asarray(g, dtype=float) for g in groups]
    if any(a.size == 0 for a in arrays):
        raise ValueError("every group needs at least one run")
    point = statistic(*arrays)
    rng = np.random.default_rng(seed)
    values = np.empty(resamples)
    for i in range(resamples):
        values[i] = statistic(*(a[rng.integers(0, a.size, a.size)] for a in arrays))
    return percentile_interval(point, values)


def bootstrap_rows(statistic: Callable[..., np.ndarray], *groups: Sequence[float], resamples: int = RESAMPLES,
                   seed: int = SEED) -> tuple[float, float, float]:
    """``bootstrap`` with a statistic of whole resample matrices (resamples x runs per group,
    one result per row): the same draws in the same order, so the same interval, without a
    Python call of the statistic per resample (20 runs a group, measured in one process: 0.30 of
    bootstrap's time for a median, 0.76 for a ratio of means, when the draws were the rest; they
    are one call now, ``_draws``)."""
    arrays = [np.asarray(g, dtype=float) for g in groups]
    if any(a.size == 0 for a in arrays):
        raise ValueError("every group needs at least one run")
    point = float(statistic(*(a[None, :] for a in arrays))[0])
    picks = _draws([a.size for a in arrays], resamples, seed)
    return percentile_interval(point, np.asarray(statistic(*(a[p] for a, p in zip(arrays, picks))), dtype=float))


def _draws(sizes: list[int], resamples: int, seed: int) -> list[np.ndarray]:
    """Each group's resamples x runs indices in bootstrap's order (per resample, each group in
    turn). Groups of one size come from one call: numpy's bounded integers continue one stream
    across calls, so one call of resamples x all runs gives the same draws as the loop, 40 times
    faster (tests/test_reproduction.py holds them equal)."""
    rng = np.random.default_rng(seed)
    if len(set(sizes)) == 1:
        return np.split(rng.integers(0, sizes[0], (resamples, sum(sizes))), len(sizes), axis=1)
    picks = [np.empty((resamples, n), dtype=np.int64) for n in sizes]
    for i in range(resamples):
        for pick, n in zip(picks, sizes):
            pick[i] = rng.integers(0, n, n)
    return picks


def percentile_interval(point: float, values: np.ndarray) -> tuple[float, float, float]:
    """(point, low, high): the 95 % percentile interval of resampled ``values``, nan and +inf
    ranked as +inf (a ratio over a zero mean, a time never reached)."""
    values = np.where(np.isnan(values), np.inf, values)
    tail = (1 - CONFIDENCE) / 2
    with np.errstate(invalid="ignore"):  # between two inf values numpy's interpolation gives nan
        low, high = np.quantile(values, tail), np.quantile(values, 1 - tail)
    return float(point), float(np.nan_to_num(low, nan=np.inf)), float(np.nan_to_num(high, nan=np.inf))


def resample_indices(runs: int, resamples: int = RESAMPLES, seed: int = SEED) -> np.ndarray:
    """resamples x runs indices of runs, drawn with replacement exactly as ``bootstrap`` draws a
    single group's (the same seed gives the same resamples)."""
    if runs <= 0:
        raise ValueError("every group needs at least one run")
    return _draws([runs], resamples, seed)[0]


@dataclass(frozen=True)
class MeanCurveTime:
    """A row's mean curve's time to threshold over its runs, with its bootstrap (verdicts R3)."""

    share_reaching: float
    """The share of resamples whose mean curve reaches the threshold."""
    interval: tuple[float, float, float]
    """(point, low, high) of the mean curve's time to threshold, +inf = never (beyond the budget)."""


def mean_curve_time(curves, steps, config: MetricsConfig = MetricsConfig(), resamples: int = RESAMPLES,
                    seed: int = SEED) -> MeanCurveTime:
    """The time to threshold of the mean of ``curves`` (runs x evaluation points) and its percentile
    bootstrap over runs: each resample's mean curve is read as the mean curve is (metrics'
    time_to_threshold), all resamples at once."""
    curves = np.asarray(curves, dtype=float)
    if curves.ndim != 2 or curves.shape[0] == 0:
        raise ValueError(f"curves must be a non-empty runs x evaluation points array, got shape {curves.shape}")
    runs = curves.shape[0]
    point = time_to_threshold(steps, curves.mean(axis=0), config.threshold, config.tolerance)
    picks = resample_indices(runs, resamples, seed)
    counts = np.zeros((resamples, runs))
    np.add.at(counts, (np.arange(resamples)[:, None], picks), 1.0)
    times = times_to_threshold_of_curves(steps, counts @ curves / runs, config.threshold, config.tolerance)
    share = float(np.isfinite(times).mean())
    return MeanCurveTime(share, percentile_interval(math.inf if point is None else point, times))


def ratio_of_means(numerator: Sequence[float], denominator: Sequence[float]) -> tuple[float, float, float]:
    """mean(numerator) / mean(denominator) with its 95 % bootstrap interval."""
    return bootstrap_rows(lambda a, b: _ratios(a.mean(axis=1), b.mean(axis=1)), numerator, denominator)


def ratio_of_medians(numerator: Sequence[float], denominator: Sequence[float]) -> tuple[float, float, float]:
    """median / median with its 95 % bootstrap interval; values may be +inf (a run that never
    reaches the threshold is slower than any that does)."""
    return bootstrap_rows(lambda a, b: _ratios(_medians(a), _medians(b)), numerator, denominator)


def median_interval(values: Sequence[float]) -> tuple[float, float, float]:
    """The median with its 95 % bootstrap interval, +inf values included (never: slower)."""
    return bootstrap_rows(_medians, values)


def format_interval(interval: tuple[float, float, float]) -> str:
    """``point [low, high]`` to two decimals; an infinite bound prints as ∞, an undefined one as n/a."""
    point, low, high = interval
    fmt = lambda v: "∞" if math.isinf(v) else ("n/a" if math.isnan(v) else f"{v:.2f}")  # noqa: E731
    return f"{fmt(point)} [{fmt(low)}, {fmt(high)}]"


def median(values: np.ndarray) -> float:
    """The median, +inf values included (a run that never reaches the threshold is slower)."""
    with np.errstate(invalid="ignore"):  # as in bootstrap's quantiles
        return float(np.median(values))


def _medians(rows: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore"):  # as ``median``
        return np.median(rows, axis=1)


def _ratios(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``_ratio`` elementwise."""
    with np.errstate(divide="ignore", invalid="ignore"):
        out = a / b
    out = np.where(np.isinf(a) & np.isinf(b), np.nan, out)
    return np.where(b == 0, np.where(a > 0, np.inf, np.nan), out)


def _ratio(a: float, b: float) -> float:
    if math.isinf(a) and math.isinf(b):
        return math.nan
    if b == 0:
        return math.inf if a > 0 else math.nan
    return a / b


def seeds_to_decide(p1: float, p2: float, alpha: float = 0.05, power: float = 0.8) -> int | None:
    """Runs per group a two-sided two-proportion z-test needs to tell failure rates ``p1`` and
    ``p2`` apart with ``power``; None when the rates are equal (no number of seeds decides)."""
    if p1 == p2:
        return None
    z_a, z_b = stats.norm.ppf(1 - alpha / 2), stats.norm.ppf(power)
    p = (p1 + p2) / 2
    n = (z_a * math.sqrt(2 * p * (1 - p)) + z_b * math.sqrt(p1 * (1 - p1) + p2 * (1 - p2))) ** 2 / (p1 - p2) ** 2
    return int(math.ceil(n))
