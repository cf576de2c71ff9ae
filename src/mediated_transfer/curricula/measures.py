"""What the curricula study measures per arm, and its registered decision rule
(conf/experiment/curricula.yaml), from the runs' results. Intervals are the reproduction
report's own (reporting/intervals.py: percentile bootstrap, runs resampled within each arm)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..metrics import _median_time as median_time  # a never-reached run counts as slower
from ..metrics import first_point_at_threshold, time_to_threshold
from ..reporting.intervals import bootstrap, iqm, ratio_of_means, sem
from ..results import RunResult

BEATS, WORSE, UNDECIDED = "beats", "worse", "undecided"


@dataclass(frozen=True)
class ArmMeasures:
    cell: str
    runs: int
    failed: int
    reward_loss_mean: float
    reward_loss_sem: float
    reward_loss_iqm: float
    mean_curve_time: int | None
    """Time to threshold of the arm's mean curve (the paper's); None: it never stays above."""
    per_run_time_median: float | None
    reached: int
    """Runs whose own curve stays above the threshold by the end."""
    never_learn: int
    """Runs with no evaluation point at <R> >= threshold."""
    discovery_median: float | None
    """Median learning step of the first rewarded target-task episode."""
    learning_median: float | None
    """Median steps from that reward to the first evaluation point at <R> >= threshold."""
    done_runs: int
    """Runs whose strategy said it was done (C solved; the reverse curriculum at the annulus)."""
    done_median: float | None
    """Median learning step at which it did (a run where it never did counts as later)."""


@dataclass(frozen=True)
class Comparison:
    """One curriculum against one reference arm: the ratio of mean L_R and the rule's word."""

    cell: str
    reference: str
    ratio: tuple[float, float, float]
    word: str


def arm_measures(cell: str, runs: Sequence[RunResult], failed: int, threshold: float) -> ArmMeasures:
    losses = np.array([r.reward_loss for r in runs])
    curves = np.array([r.mean_reward for r in runs])
    steps = runs[0].steps
    per_run = [time_to_threshold(r.steps, r.mean_reward, threshold) for r in runs]
    return ArmMeasures(
        cell=cell, runs=len(runs), failed=failed, reward_loss_mean=float(losses.mean()),
        reward_loss_sem=sem(losses), reward_loss_iqm=iqm(losses),
        mean_curve_time=time_to_threshold(steps, curves.mean(axis=0), threshold),
        per_run_time_median=median_time(per_run), reached=sum(t is not None for t in per_run),
        never_learn=sum(first_point_at_threshold(r.mean_reward, threshold) is None for r in runs),
        discovery_median=median_time([r.first_target_reward_step for r in runs]),
        learning_median=median_time([r.learning_span(threshold) for r in runs]),
        done_runs=sum(r.source_phase_end is not None for r in runs),
        done_median=median_time([r.source_phase_end for r in runs]))


def word(interval: tuple[float, float, float]) -> str:
    """The registered rule on a ratio of mean L_R (lower is better): BEATS when the whole 95 %
    interval lies below 1, WORSE when it lies above 1, otherwise UNDECIDED."""
    _, low, high = interval
    if high < 1:
        return BEATS
    if low > 1:
        return WORSE
    return UNDECIDED


def compare(cell: str, runs: Sequence[RunResult], reference: str,
            reference_runs: Sequence[RunResult]) -> Comparison:
    ratio = ratio_of_means([r.reward_loss for r in runs], [r.reward_loss for r in reference_runs])
    return Comparison(cell, reference, ratio, word(ratio))


def time_ratio(runs: Sequence[RunResult], reference_runs: Sequence[RunResult], threshold: float,
               budget: int) -> tuple[float, float, float]:
    """Secondary, outside the rule: the mean curve's time to threshold over the reference's,
    with its bootstrap interval (runs resampled within each arm; a mean curve that never stays
    above the threshold counts as the budget, so the ratio is then a bound)."""
    curves = np.array([r.mean_reward for r in runs])
    reference = np.array([r.mean_reward for r in reference_runs])
    steps = runs[0].steps

    def time_of(c: np.ndarray) -> float:
        t = time_to_threshold(steps, c.mean(axis=0), threshold)
        return float(budget if t is None else t)

    def ratio(i: np.ndarray, j: np.ndarray) -> float:
        return time_of(curves[i.astype(int)]) / time_of(reference[j.astype(int)])

    return bootstrap(ratio, np.arange(len(runs)), np.arange(len(reference_runs)))


def verdict(words: dict[str, list[str]]) -> tuple[str, dict[str, str]]:
    """The registered verdict from each learner's words against the scaffolding: per learner
    YES when a curriculum beats it, NO otherwise; overall YES when YES for either learner."""
    per_learner = {learner: "YES" if BEATS in w else "NO" for learner, w in words.items()}
    overall = "YES" if "YES" in per_learner.values() else "NO"
    return overall, per_learner


def steps_text(value: float | None) -> str:
    return "never" if value is None or (isinstance(value, float) and math.isinf(value)) else f"{int(value):,}"
