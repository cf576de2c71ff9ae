"""One trial: the target task learned without transfer at every tuning seed, scored by reward loss.

The objective is the mean reward loss L_R over the tuning seeds. Beside it a trial records, per
seed, the evaluation curve, L_R, the learning step of the first rewarded target-task episode
(discovery: when the learner first solved the mediated interaction by chance), the first
evaluation step with <R> >= threshold, and the span between the two (learning: how long it then
took to learn the tool skill). Issue 9 found that transfer shortens discovery, not learning; the
split shows which of the two a hyperparameter moves.

A run stopped because its learner diverged (RunResult.failure) scores <R> = 0 at the evaluation
points it did not reach: a diverged learner has no policy left, and the search should see the
setting as the bad one it is, not lose the trial.

A trial whose mean L_R can no longer fall below the study's best is stopped early: each
evaluation point adds R_max - <R> >= 0 to a run's L_R, so the L_R of the seeds done plus the
partial L_R of the seed running, over the number of seeds, is a lower bound of the trial's
objective. Once that bound exceeds the best finished trial's objective, the trial cannot be the
best; the rest of its runs would change nothing the search selects, and cost hours for the DQN.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from ..metrics import first_point_at_threshold
from ..sweep.orphan import launcher_watch
from ..results import RunResult
from .space import SearchSpace


PartialLossFn = Callable[[int, float], None]
"""Called at each evaluation point of a run with (learning step, L_R of the points so far)."""


def run_seed(overrides: Sequence[str], on_partial_loss: PartialLossFn | None = None) -> tuple[RunResult, float]:
    """Compose the config of one run and execute it; returns its result and its threshold.

    The only place where the tuning turns a config into a learning run.
    """
    from ..config.spec import run_spec
    from ..run import execute_run
    from ..config.compose import compose_config

    cfg = compose_config(overrides)
    spec = run_spec(cfg)
    max_reward = float(cfg.env.success_reward)
    orphaned = launcher_watch()
    partial = 0.0

    def watch(step: int, reward: float, _success: float) -> None:
        nonlocal partial
        # The study's process was killed: this worker would compute on unseen, for hours.
        if orphaned():
            raise KeyboardInterrupt("the tuning's launching process is gone")
        partial += max_reward - reward
        if on_partial_loss is not None:
            on_partial_loss(step, partial)

    result = execute_run(spec, on_evaluation=watch)
    return (_scored_to_the_end(result, spec.budget, spec.eval_points, max_reward)
            if result.failed else result), float(cfg.threshold)


def _scored_to_the_end(result: RunResult, budget: int, eval_points: int, max_reward: float) -> RunResult:
    """A failed run's curve completed with <R> = 0 (and success 0) at the points it did not reach."""
    from dataclasses import replace

    from ..metrics import reward_loss

    every = budget // eval_points
    missing = [every * k for k in range(len(result.steps) + 1, eval_points + 1)]
    rewards = list(result.mean_reward) + [0.0] * len(missing)
    return replace(result, steps=list(result.steps) + missing, mean_reward=rewards,
                   success_rate=list(result.success_rate) + [0.0] * len(missing),
                   reward_loss=reward_loss(np.asarray(rewards), max_reward))


def first_step_at_threshold(steps: Sequence[int], rewards: Sequence[float], threshold: float) -> int | None:
    """The learning step of the first evaluation point with <R> >= threshold (reached once,
    stable or not); None: never."""
    point = first_point_at_threshold(rewards, threshold)
    return None if point is None else int(steps[point])


def trial_record(seeds: Sequence[int], results: Sequence[RunResult], threshold: float) -> dict[str, Any]:
    """What a trial keeps: per-seed lists (in the order of ``seeds``) and the mean curve."""
    steps = list(results[0].steps)
    if any(list(r.steps) != steps for r in results):
        raise ValueError("the runs of a trial must share their evaluation steps")
    at_threshold = [first_step_at_threshold(r.steps, r.mean_reward, threshold) for r in results]
    discovery = [r.first_target_reward_step for r in results]
    return {
        "seeds": [int(s) for s in seeds],
        "steps": steps,
        "mean_curve": [float(v) for v in np.mean([r.mean_reward for r in results], axis=0)],
        "curves": [[float(v) for v in r.mean_reward] for r in results],
        "reward_loss": [float(r.reward_loss) for r in results],
        "first_target_reward_step": discovery,
        "first_threshold_step": at_threshold,
        "learning_span": [r.learning_span(threshold) for r in results],
        "time_to_threshold": [r.time_to_threshold for r in results],
        "final_reward": [float(r.mean_reward[-1]) for r in results],
        "wall_time_s": [float(r.wall_time_s) for r in results],
        "failure": [r.failure for r in results],
        "threshold": threshold,
    }


class StoppedEarly(Exception):
    """The trial's mean L_R is already above ``ceiling``: it cannot be the study's best."""

    def __init__(self, lower_bound: float, ceiling: float, seed: int, step: int, record: dict[str, Any]):
        super().__init__(f"mean L_R >= {lower_bound:.1f} > best {ceiling:.1f} at seed {seed}, step {step:,}")
        self.lower_bound, self.ceiling, self.seed, self.step = lower_bound, ceiling, seed, step
        self.record = record
        """trial_record of the seeds finished before the stop ({} when none was)."""


CeilingFn = Callable[[], float | None]
"""The objective a trial must stay below to matter (the study's best so far); None: no limit."""


def evaluate(space: SearchSpace, values: Mapping[str, Any],
             ceiling: CeilingFn | None = None) -> tuple[float, dict[str, Any]]:
    """Run a trial with ``values`` at every tuning seed: (mean L_R, the trial's record).

    With ``ceiling``, raises StoppedEarly as soon as the trial's lower bound exceeds it.
    """
    results: list[RunResult] = []
    threshold = None
    count = len(space.seeds)

    def check(seed: int, step: int, loss_so_far: float) -> None:
        limit = ceiling() if ceiling is not None else None
        bound = (sum(r.reward_loss for r in results) + loss_so_far) / count
        if limit is not None and bound > limit:
            done = space.seeds[:len(results)]
            raise StoppedEarly(bound, limit, seed, step,
                               trial_record(done, results, threshold) if results else {})

    for index, seed in enumerate(space.seeds):
        result, threshold = run_seed(space.run_overrides(values, seed),
                                     None if ceiling is None else lambda step, loss: check(seed, step, loss))
        results.append(result)
        if ceiling is not None and index + 1 < count:
            # A diverged run's missing points (scored 0) are known only at its end.
            check(seed, result.steps[-1], 0.0)
    record = trial_record(space.seeds, results, threshold)
    return float(np.mean(record["reward_loss"])), record
