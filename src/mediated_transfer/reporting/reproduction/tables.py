"""The report's tables of measures, beside the claims: every row of Tables II-IV against the
paper's, where a run's time goes per learner (discovery, learning, holding), and the DQN's runs
that never learn without transfer (whose columns the DQN failure ablation reuses)."""

from __future__ import annotations

import math

import numpy as np

from ...metrics import learning_span, loss_after_learning
from ..intervals import format_interval, iqm, median_interval, probability_of_improvement, ratio_of_means, sem
from .runs import MAX_REWARD, THRESHOLD, Learner, never_learns
from .wording import steps_k

NEVER_LEARN_COLUMNS = ("| seed | L_R | first rewarded target episode | final <R> | episodes | final TD loss |",
                       "|---:|---:|---|---:|---:|---:|")


def never_learn_row(run) -> str:
    """A run that never learns, as a row under NEVER_LEARN_COLUMNS: when it first found the
    reward, and the learner's state at the end (episodes run, last TD loss)."""
    s = run.learner_stats
    return (f"| {run.seed} | {run.reward_loss:.1f} | {steps_k(run.first_target_reward_step)} | "
            f"{run.mean_reward[-1]:.2f} | {s.get('episodes', math.nan):,.0f} | {s.get('last_loss', math.nan):.1e} |")


def cell_table(lr: Learner) -> list[str]:
    """Every row of the learner's table: reward loss against the paper's and against the row
    without transfer, runs that never learn, time to threshold."""
    out = [f"| {lr.name} row | runs | L_R mean ± SEM | IQM | paper | ratio to none_0 [95 % CI] | "
           "P(improvement) | never learn | time to threshold: mean curve / median per run [95 % CI] |",
           "|---|---:|---:|---:|---:|---|---:|---:|---|"]
    for cell, p in lr.paper.items():
        runs = lr.runs(cell)
        if not runs:
            out.append(f"| {cell} | 0 | | | {p.reward_loss_mean:.1f} | | | | |")
            continue
        losses = lr.reward_losses(cell)
        ratio = "" if cell == "none_0" else format_interval(ratio_of_means(losses, lr.reward_losses("none_0")))
        improve = "" if cell == "none_0" else f"{probability_of_improvement(losses, lr.reward_losses('none_0')):.2f}"
        failed = f" (+{len(lr.cells[cell].failed)} diverged)" if lr.cells[cell].failed else ""
        out.append(f"| {cell} | {len(runs)}{failed} | {losses.mean():.1f} ± {sem(losses):.1f} | {iqm(losses):.1f} | "
                   f"{p.reward_loss_mean:.1f} | {ratio} | {improve} | {lr.never_learn(cell)} | "
                   f"{steps_k(lr.mean_curve_time(cell))} / {_median_time_interval(lr.times_to_threshold(cell))} |")
    return out


def split_table(learners: dict[str, Learner]) -> list[str]:
    """Where a run's time goes: until the first rewarded target episode (discovery), from there to
    the first <R> >= 8 (learning), and the L_R lost after that point (holding); medians over the
    runs that get there."""
    out = ["| learner | row | runs | discovery: first rewarded target episode | learning: discovery -> "
           "first <R> >= 8 | holding: L_R lost after that point |", "|---|---|---:|---|---|---|"]
    for lr in learners.values():
        for cell in ("none_0", "regular_50", "scaffolded_50"):
            runs = lr.runs(cell)
            if not runs:
                continue
            discovery = [r.first_target_reward_step for r in runs if r.first_target_reward_step is not None]
            spans = [s for r in runs if (s := learning_span(r.first_target_reward_step, r.steps, r.mean_reward,
                                                            THRESHOLD)) is not None]
            holding = [h for r in runs if (h := loss_after_learning(r.mean_reward, THRESHOLD, MAX_REWARD)) is not None]
            out.append(f"| {lr.name} | {cell} | {len(runs)} | median {steps_k(_median(discovery))} "
                       f"({len(discovery)} of {len(runs)} discover) | median {steps_k(_median(spans))} "
                       f"({len(spans)} get there) | median {_median(holding, 1)} |")
    return out


def dqn_failures(learners: dict[str, Learner]) -> list[str]:
    """The DQN's runs without transfer that never learn, one row each, and the study of why."""
    dnn = learners["IV"]
    runs = dnn.runs("none_0")
    never = [r for r in runs if never_learns(r)]
    return [f"Without transfer, {len(never)} of {len(runs)} DQN runs never reach <R> >= 8; with transfer, "
            f"{sum(dnn.never_learn(c) for c in dnn.cells if c != 'none_0')} of "
            f"{sum(len(dnn.runs(c)) for c in dnn.cells if c != 'none_0')} runs.", "",
            *NEVER_LEARN_COLUMNS, *map(never_learn_row, never), "",
            "Why: a pre-registered ablation of the replay buffer and the ε schedule on fresh seeds, "
            "[dqn_failure_ablation.md](dqn_failure_ablation.md) (`make dqn-ablation`)."]


def _median_time_interval(times: np.ndarray) -> str:
    """The median per-run time to threshold with its bootstrap interval (never: slower than any)."""
    point, low, high = median_interval(times)
    return f"{steps_k(point)} [{steps_k(low)}, {steps_k(high)}]"


def _median(values: list, digits: int | None = None):
    if not values:
        return None if digits is None else "n/a"
    m = float(np.median(values))
    return m if digits is None else f"{m:.{digits}f}"
