"""What the study measures per world, from its runs' results: discovery rarity, post-discovery
learning, and each transfer arm's gain over learning without transfer, with bootstrap
confidence intervals over seeds (conf/experiment/sensitivity.yaml says why each)."""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from ..metrics import time_to_threshold
from ..reporting.paper import paper_rows
from ..results import RunResult
from .study import World

PAPER_TABLE = "II"
"""The paper's table of the study's learner (linear Q(lambda) + RBF)."""


@dataclass(frozen=True)
class Measures:
    """The study's analysis parameters, fixed with the study (one place)."""

    random_episodes: int = 100_000
    """Target episodes of the uniformly random policy per world (about a minute each, cached):
    at today's rate of about 0.2 % that is some 200 successes, and still about 20 at a rate ten
    times smaller, enough to tell the worlds' rarity apart by a factor of 2."""
    random_seed: int = 2026
    """Seed of the random policy's episodes (not a learning seed of any run)."""
    confidence: float = 0.95
    resamples: int = 10_000
    """Bootstrap resamples per interval."""
    bootstrap_seed: int = 0


@dataclass(frozen=True)
class Interval:
    value: float
    low: float
    high: float

    def contains(self, x: float) -> bool:
        return self.low <= x <= self.high


def threshold_time(curves: np.ndarray, steps: Sequence[int], threshold: float, budget: int) -> int:
    """The paper's time to threshold of the mean curve of ``curves`` (runs x points); the
    budget when the mean curve never stays above the threshold (a bound, not a time)."""
    time = time_to_threshold(steps, curves.mean(axis=0), threshold)
    return budget if time is None else time


def ratio_interval(arm: np.ndarray, none: np.ndarray, statistic: Callable[[np.ndarray], float],
                   measures: Measures) -> Interval:
    """statistic(arm runs) / statistic(none runs), with its bootstrap confidence interval: runs
    resampled with replacement within each arm (the arms are independent samples), BCa, and the
    percentile interval where BCa is undefined (e.g. every resample ties)."""
    arm, none = np.asarray(arm), np.asarray(none)

    def ratio(i: np.ndarray, j: np.ndarray) -> float:
        return statistic(arm[i.astype(int)]) / statistic(none[j.astype(int)])

    value = float(ratio(np.arange(len(arm)), np.arange(len(none))))
    if len(arm) < 2 or len(none) < 2:
        return Interval(value, math.nan, math.nan)
    data = (np.arange(len(arm)), np.arange(len(none)))
    for method in ("BCa", "percentile"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # BCa's degenerate-distribution warning: handled below
            result = stats.bootstrap(data, ratio, n_resamples=measures.resamples, vectorized=False,
                                     paired=False, confidence_level=measures.confidence, method=method,
                                     rng=np.random.default_rng(measures.bootstrap_seed))
        low, high = result.confidence_interval
        if np.isfinite(low) and np.isfinite(high):
            return Interval(value, float(low), float(high))
    return Interval(value, float(low), float(high))


@dataclass(frozen=True)
class ArmGain:
    """One transfer arm of one world against that world's runs without transfer."""

    cell: str
    runs: int
    reward_loss_mean: float
    reward_loss_ratio: Interval
    threshold_time: int
    threshold_time_ratio: Interval
    threshold_reached: bool
    """Whether the arm's mean curve stays above the threshold by the end (else the time is the
    budget, and the ratio a bound)."""


def arm_gain(cell: str, arm: Sequence[RunResult], none: Sequence[RunResult], threshold: float,
             budget: int, measures: Measures) -> ArmGain:
    steps = arm[0].steps
    losses_arm = np.array([r.reward_loss for r in arm])
    losses_none = np.array([r.reward_loss for r in none])
    curves_arm = np.array([r.mean_reward for r in arm])
    curves_none = np.array([r.mean_reward for r in none])

    def time_of(curves: np.ndarray) -> float:
        return float(threshold_time(curves, steps, threshold, budget))

    time = threshold_time(curves_arm, steps, threshold, budget)
    return ArmGain(
        cell=cell, runs=len(arm), reward_loss_mean=float(losses_arm.mean()),
        reward_loss_ratio=ratio_interval(losses_arm, losses_none, np.mean, measures),
        threshold_time=time, threshold_time_ratio=ratio_interval(curves_arm, curves_none, time_of, measures),
        threshold_reached=time_to_threshold(steps, curves_arm.mean(axis=0), threshold) is not None)


def paper_gains() -> dict[str, tuple[float, float | None]]:
    """The paper's gain of each transfer row of Table II over its row without transfer:
    (L_R ratio, time-to-threshold ratio or None)."""
    rows = {r.cell: r for r in paper_rows(PAPER_TABLE)}
    none = rows["none_0"]
    gains = {}
    for cell, row in rows.items():
        if cell == "none_0":
            continue
        time = (row.time_to_threshold / none.time_to_threshold
                if row.time_to_threshold and none.time_to_threshold else None)
        gains[cell] = (row.reward_loss_mean / none.reward_loss_mean, time)
    return gains


@dataclass
class WorldResult:
    world: World
    changes: str
    random_success: float
    runs: dict[str, int]
    """Finished runs per cell (failed ones not counted)."""
    failed: dict[str, int]
    discovery_median: float | None = None
    """Median learning step of the first rewarded target episode, without transfer."""
    learning_median: float | None = None
    """Median steps from that reward to the first <R> >= threshold, without transfer."""
    reward_loss_none: float | None = None
    reward_loss_none_sem: float | None = None
    gains: dict[str, ArmGain] = field(default_factory=dict)
