"""What the curricula studies measure per arm, and their registered decision rules
(conf/experiment/curricula2.yaml; the first study's, curricula.yaml, are the same words), from
the runs' results. Intervals are the reproduction
report's own (reporting/intervals.py: percentile bootstrap, runs resampled within each arm)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..metrics import first_point_at_threshold, median_time, time_to_threshold
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
    exposure_median: float | None
    """Median over runs of the share of training episodes on target-annulus tasks (exposure)."""
    exposure_counts_all: bool
    """The exposure counts every annulus episode; False: a record from before annulus_share,
    which counts only the environment's target tasks (a curriculum's own annulus tasks read 0)."""
    annulus_solved_median: float | None
    """Median learning step by which a run first solved an annulus task, whoever drew it (the end
    of the first evaluation interval with one; never counts as later)."""


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
        done_median=median_time([r.source_phase_end for r in runs]),
        exposure_median=_median([exposure(r) for r in runs]),
        exposure_counts_all=all("annulus_share" in (r.choices or {}) for r in runs),
        annulus_solved_median=median_time([first_annulus_success(r) for r in runs]))


def _median(values: Sequence[float | None]) -> float | None:
    known = [v for v in values if v is not None]
    return float(np.median(known)) if known else None


def exposure(run: RunResult) -> float | None:
    """The share of the run's training episodes whose target lay in the target annulus, whoever
    drew the task (result.json choices ``annulus_share``); a record from before that column gives
    its environment-drawn target tasks' share (``target_share``). None: no record."""
    choices = run.choices or {}
    episodes = np.array(choices.get("episodes") or [], dtype=float)
    share = choices.get("annulus_share", choices.get("target_share"))
    if share is None or episodes.sum() == 0:
        return None
    share = np.array([0.0 if v is None else v for v in share], dtype=float)
    return float((share * episodes).sum() / episodes.sum())


def first_annulus_success(run: RunResult) -> int | None:
    """The end of the first evaluation interval in which the run solved an annulus task (None:
    never, or no record of it)."""
    choices = run.choices or {}
    for b, solved in enumerate(choices.get("annulus_solved") or []):
        if solved:
            return (b + 1) * int(choices["every"])
    return None


RULE = ("The registered rule: an arm *beats* scaffolded transfer (N_source = 100) for a learner in a world when "
        "the 95 % bootstrap interval of its mean L_R over scaffolded's lies entirely below 1, is *worse* when it "
        "lies entirely above 1, and is *undecided* otherwise; the same words against regular transfer.")
"""The rule as the report states it (conf/experiment/curricula2.yaml's words); ``word`` applies it."""


def word(interval: tuple[float, float, float]) -> str:
    """The registered rule on a ratio of mean L_R (lower is better): BEATS when the whole 95 %
    interval lies below 1, WORSE when it lies above 1, otherwise UNDECIDED (an undefined
    interval, NaN, included)."""
    _, low, high = interval
    if high < 1:
        return BEATS
    if low > 1:
        return WORSE
    return UNDECIDED


MIN_RUNS = 2
"""Runs each arm needs for an interval: one run per arm has no spread, its bootstrap interval
is a point, and the rule would decide on one seed."""


def compare(cell: str, runs: Sequence[RunResult], reference: str,
            reference_runs: Sequence[RunResult]) -> Comparison:
    losses, reference_losses = [r.reward_loss for r in runs], [r.reward_loss for r in reference_runs]
    if min(len(losses), len(reference_losses)) < MIN_RUNS:
        ratio = (float(np.mean(losses) / np.mean(reference_losses)), math.nan, math.nan)  # undecided, n/a
    else:
        ratio = ratio_of_means(losses, reference_losses)
    return Comparison(cell, reference, ratio, word(ratio))


def time_ratio(runs: Sequence[RunResult], reference_runs: Sequence[RunResult], threshold: float,
               budget: int) -> tuple[float, float, float]:
    """Secondary, outside the rule: the mean curve's time to threshold over the reference's,
    with its bootstrap interval (runs resampled within each arm; a mean curve that never stays
    above the threshold counts as the budget, so the ratio is then a bound)."""
    if min(len(runs), len(reference_runs)) < MIN_RUNS:
        return math.nan, math.nan, math.nan  # as compare: no interval from one run
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
    """The registered verdict from each group's (a learner, in a world) words against the
    scaffolding: per group YES when an arm beats it, NO otherwise; overall YES when YES for any."""
    per_group = {group: "YES" if BEATS in w else "NO" for group, w in words.items()}
    overall = "YES" if "YES" in per_group.values() else "NO"
    return overall, per_group


def dqn_picks(ratios: dict[str, dict[str, float]], order: Sequence[str], count: int = 2) -> list[str]:
    """The registered rule for the DQN's curricula: the ``count`` curricula of lowest geometric
    mean of r_S over the groups given (RBF and FSR in the default world); ties in ``order``.
    ``ratios``: group -> curriculum -> r_S (mean L_R over scaffolded's)."""
    def score(cell: str) -> float:
        values = [group[cell] for group in ratios.values() if cell in group]
        return float(np.exp(np.mean(np.log(values)))) if len(values) == len(ratios) else math.inf
    ranked = sorted((c for c in order if math.isfinite(score(c))), key=lambda c: (score(c), order.index(c)))
    return ranked[:count]


def exposure_correlation(exposures: Sequence[float], losses: Sequence[float]) -> float | None:
    """Secondary: Spearman's rank correlation of the arms' median exposure and mean L_R."""
    from scipy.stats import spearmanr

    if len(exposures) < 3 or len(set(exposures)) < 2 or len(set(losses)) < 2:
        return None  # undefined for a constant input
    rho = spearmanr(exposures, losses).statistic
    return None if not np.isfinite(rho) else float(rho)


def steps_text(value: float | None) -> str:
    return "never" if value is None or (isinstance(value, float) and math.isinf(value)) else f"{int(value):,}"
