"""The paper's two performance metrics (Sec. IV-C): total reward loss and time to threshold.

A learning curve is <R_i>, the mean target-task reward at the evaluation points i (learning
steps ``steps[i]``). Per run: L_R = sum_i (R_max - <R_i>) and the run's time to threshold.
Per configuration (many runs): the mean and standard error of L_R, and the time to threshold
of the mean curve, which is what the paper's tables and figures report; the median of the
per-run times to threshold is reported next to it.

"Time to threshold" is read as in NOTES: the first evaluation point from which the curve
stays >= the threshold until the end of the budget. A curve that dips below later has not
reached it yet at the earlier point; a curve that is below at the last point never reached
it (None, printed "-").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class MetricsConfig:
    max_reward: float = 10.0
    """R_max of the reward loss: the success reward of one episode."""
    threshold: float = 8.0
    """<R> that time to threshold asks for: the paper's 80 % success rate times R_max = 10."""
    tolerance: float = 1e-9
    """Slack below the threshold still counted as reaching it: averaging runs leaves float
    round-off (a true mean of exactly 8 can come out as 7.999999999999999)."""

    def __post_init__(self) -> None:
        if not self.max_reward > 0:
            raise ValueError(f"metrics.max_reward must be > 0, got {self.max_reward!r}")
        if not 0 < self.threshold <= self.max_reward:
            raise ValueError(
                f"metrics.threshold must lie in (0, max_reward={self.max_reward:g}], "
                f"got {self.threshold!r}"
            )
        if not 0 <= self.tolerance < self.threshold:
            raise ValueError(f"metrics.tolerance must lie in [0, threshold), got {self.tolerance!r}")


_DEFAULT = MetricsConfig()


def reward_loss(mean_rewards, max_reward: float = _DEFAULT.max_reward) -> float:
    """Total reward loss L_R = sum_i (R_max - <R_i>) of one curve (0 .. points * R_max)."""
    rewards = _curve(mean_rewards, "mean_rewards")
    # <R> is an average of episode rewards in {0, R_max}: anything outside means a wrong input
    # (e.g. a success rate in percent, or a curve of another reward scale).
    slack = _DEFAULT.tolerance * max(1.0, max_reward)
    if rewards.min() < -slack or rewards.max() > max_reward + slack:
        raise ValueError(
            f"mean_rewards must lie in [0, max_reward={max_reward:g}], got values in "
            f"[{rewards.min():g}, {rewards.max():g}]"
        )
    return float(np.sum(max_reward - rewards))


def time_to_threshold(
    steps,
    mean_rewards,
    threshold: float = _DEFAULT.threshold,
    tolerance: float = _DEFAULT.tolerance,
) -> int | None:
    """The learning step of the first evaluation point from which the curve stays >= threshold
    until the end; None when the last point is below the threshold (never reached)."""
    steps = _steps(steps)
    rewards = _curve(mean_rewards, "mean_rewards")
    if len(steps) != len(rewards):
        raise ValueError(
            f"steps and mean_rewards must have the same length, got {len(steps)} and {len(rewards)}"
        )
    below = np.flatnonzero(rewards < threshold - tolerance)
    if below.size == 0:
        return int(steps[0])
    last_below = int(below[-1])
    if last_below == len(rewards) - 1:
        return None
    return int(steps[last_below + 1])


def times_to_threshold_of_curves(
    steps,
    curves,
    threshold: float = _DEFAULT.threshold,
    tolerance: float = _DEFAULT.tolerance,
) -> np.ndarray:
    """``time_to_threshold`` of each row of a curves x evaluation points array at once (e.g. the
    mean curves of many bootstrap resamples), as floats: +inf where a curve never reaches it."""
    steps = _steps(steps)
    rewards = np.asarray(curves, dtype=float)
    if rewards.ndim != 2 or rewards.shape[1] != len(steps) or not np.all(np.isfinite(rewards)):
        raise ValueError(f"curves must be a finite curves x {len(steps)} points array, got shape {rewards.shape}")
    below = rewards < threshold - tolerance
    points = len(steps)
    # the index of each curve's last point below the threshold, -1 where none is
    last_below = np.where(below.any(axis=1), points - 1 - np.argmax(below[:, ::-1], axis=1), -1)
    times = np.full(len(rewards), math.inf)
    reached = last_below < points - 1
    times[reached] = steps[last_below[reached] + 1]
    return times


def first_point_at_threshold(mean_rewards, threshold: float = _DEFAULT.threshold) -> int | None:
    """Index of the first evaluation point with <R> >= threshold, reached once (unlike time to
    threshold, the curve may fall below it again later); None: never."""
    return next((i for i, r in enumerate(mean_rewards) if r >= threshold), None)


def learning_span(first_target_reward_step: int | None, steps, mean_rewards,
                  threshold: float = _DEFAULT.threshold) -> int | None:
    """Learning steps from the first rewarded target-task episode (discovery) to the first
    evaluation point with <R> >= threshold: how fast the tool skill is learned once discovered.
    0 when that point comes first (a transferred skill can pass an evaluation before a target
    episode of learning is rewarded); None when the run never gets there or was never rewarded
    on a target task."""
    reached = first_point_at_threshold(mean_rewards, threshold)
    if first_target_reward_step is None or reached is None:
        return None
    return max(0, int(steps[reached]) - int(first_target_reward_step))


def loss_after_learning(mean_rewards, threshold: float = _DEFAULT.threshold,
                        max_reward: float = _DEFAULT.max_reward) -> float | None:
    """The part of L_R from the first evaluation point with <R> >= threshold to the end: what a
    run still loses once it has learned the task (greedy collapses, a lower plateau). None when
    the run never gets there."""
    reached = first_point_at_threshold(mean_rewards, threshold)
    return None if reached is None else float(sum(max_reward - r for r in mean_rewards[reached:]))


def summarise_runs(curves, steps, config: MetricsConfig = _DEFAULT) -> dict:
    """Everything the result tables need about one configuration, from its runs' curves.

    ``curves``: runs x evaluation points array of <R>; ``steps``: the evaluation points'
    learning steps (shared by all runs). Returns a dict with

    - ``n_runs``; ``steps`` (int array);
    - ``mean_curve``, ``sem_curve``: mean over runs and its standard error per point;
    - ``reward_loss``: L_R per run (array); ``reward_loss_mean``, ``reward_loss_sem``;
    - ``final_reward_mean``, ``final_reward_sem``: <R> at the last evaluation point;
    - ``time_to_threshold``: of the mean curve (the paper's number), int step or None;
    - ``time_to_threshold_runs``: per run, int step or None;
    - ``runs_reaching_threshold``: how many runs have a per-run time to threshold;
    - ``time_to_threshold_median``: median of the per-run values, a never-reaching run
      counted as +inf (it is slower than any that reaches); None when that median is
      infinite, i.e. when at least half of the runs never reach the threshold.

    Standard error = sample std (ddof=1) / sqrt(n). With a single run it is undefined and
    reported as nan (not 0, which would claim a certainty one run cannot give).
    """
    curves = np.asarray(curves, dtype=float)
    if curves.ndim != 2 or curves.shape[0] == 0 or curves.shape[1] == 0:
        raise ValueError(
            f"curves must be a non-empty runs x evaluation points array, got shape {curves.shape}"
        )
    steps = _steps(steps)
    if len(steps) != curves.shape[1]:
        raise ValueError(
            f"steps has {len(steps)} evaluation points but curves has {curves.shape[1]} per run"
        )
    n_runs = curves.shape[0]
    losses = np.array([reward_loss(curve, config.max_reward) for curve in curves])
    per_run = [time_to_threshold(steps, curve, config.threshold, config.tolerance) for curve in curves]
    mean_curve = curves.mean(axis=0)
    return {
        "n_runs": n_runs,
        "steps": steps,
        "mean_curve": mean_curve,
        "sem_curve": _sem(curves),
        "reward_loss": losses,
        "reward_loss_mean": float(losses.mean()),
        "reward_loss_sem": float(_sem(losses[:, None])[0]),
        "final_reward_mean": float(mean_curve[-1]),
        "final_reward_sem": float(_sem(curves[:, -1:])[0]),
        "time_to_threshold": time_to_threshold(steps, mean_curve, config.threshold, config.tolerance),
        "time_to_threshold_runs": per_run,
        "runs_reaching_threshold": sum(t is not None for t in per_run),
        "time_to_threshold_median": median_time(per_run),
    }


def _sem(values: np.ndarray) -> np.ndarray:
    """Standard error of the mean over axis 0 (runs); nan for a single run."""
    n = values.shape[0]
    if n < 2:
        return np.full(values.shape[1], np.nan)
    return values.std(axis=0, ddof=1) / math.sqrt(n)


def median_time(per_run: list[int | None]) -> float | None:
    """Median over runs of a step (time to threshold, discovery, learning span), a run that never
    gets there (None) counted as slower than any that does; None when that median is never."""
    times = np.array([math.inf if t is None else t for t in per_run], dtype=float)
    median = float(np.median(times))
    return None if math.isinf(median) else median


def _curve(values, name: str) -> np.ndarray:
    array = np.asarray(values, dtype=float)
    if array.ndim != 1 or array.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D curve, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite, got {array.tolist()}")
    return array


def _steps(values) -> np.ndarray:
    steps = np.asarray(values)
    if steps.ndim != 1 or steps.size == 0:
        raise ValueError(f"steps must be a non-empty 1-D array, got shape {steps.shape}")
    if not np.all(np.isfinite(steps)) or np.any(steps != np.round(steps)):
        raise ValueError(f"steps must be whole learning steps, got {steps.tolist()}")
    steps = steps.astype(np.int64)
    if np.any(np.diff(steps) <= 0):
        raise ValueError(f"steps must be strictly increasing, got {steps.tolist()}")
    return steps
