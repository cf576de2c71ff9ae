"""Sampling For Learnability (SFL; Rutherford et al. 2024, "No Regrets: Investigating and
Improving Regret Approximations for Curriculum Discovery"), with its paper's generator: fresh
levels from domain randomisation over the whole task space, scored by learnability p (1 - p), a
buffer rebuilt from the newly scored ones (issue 42; the first study's learnability.py sampled
over C and one target level instead).

SFL's loop: every T updates, roll out N fresh levels of the generator, score each by p (1 - p)
(p its success rate under the current policy), and replace the buffer by the K of highest
score; train on buffer levels with probability rho, on fresh generator levels otherwise.

Here a fresh level is a task whose target distance is uniform over the task space, from the
nearest source distance to the farthest target distance (domain randomisation's draw; the
annulus is its far end). Scoring spends no steps outside the budget: the generator's share
(1 - rho) of the episodes *is* the scoring, each of a batch's ``batch_levels`` fresh levels
played ``rollouts`` times as training episodes (the learner learns from them, as from any
generator level in SFL), and when a batch is played out the buffer becomes its ``buffer_size``
levels of highest learnability > 0 (none: the buffer is empty until a batch has one). So every
environment step is a learning step, as for every other arm of the study.

Values (conf/strategy/sfl.yaml): rho = 0.5 (SFL's), K = 10 of N = 40 scored levels per batch
(SFL keeps its top 100 of 5000 per rebuild, a sharper cut that its thousands of parallel
rollouts afford; here a batch costs 200 episodes), 5 rollouts per level (p in {0, 0.2, ..., 1}).
Never done: the generator covers the target tasks.
"""

from __future__ import annotations

import numpy as np

from mediated_transfer.env import Task
from mediated_transfer.transfer import EpisodeOutcome, StrategyContext


class SamplingForLearnability:
    """``strategy=sfl`` (conf/strategy/sfl.yaml)."""

    source_tasks = "none"  # levels come from the generator: n_source=0
    done = False

    def __init__(self, context: StrategyContext, *, buffer_share: float, buffer_size: int, batch_levels: int,
                 rollouts: int):
        for key, value in (("buffer_size", buffer_size), ("batch_levels", batch_levels), ("rollouts", rollouts)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"strategy.{key} must be an integer >= 1, got {value!r}")
        if isinstance(buffer_share, bool) or not isinstance(buffer_share, (int, float)) or not 0 <= buffer_share < 1:
            raise ValueError(f"strategy.buffer_share must be a number in [0, 1), got {buffer_share!r}")
        self.rng, self.space = context.rng, context.task_space
        self.buffer_share, self.buffer_size = float(buffer_share), buffer_size
        self.batch_levels, self.rollouts = batch_levels, rollouts
        self.buffer: list[Task] = []
        self.rebuilds = 0
        self._pending: int | None = None  # the batch level of the episode handed out; -1: a buffer level
        self._new_batch()

    def _new_batch(self) -> None:
        low, high = self.space.distances
        self.batch = [self.space.sample(self.rng, float(d))
                      for d in self.rng.uniform(low, high, size=self.batch_levels)]
        self.solved = np.zeros(self.batch_levels)
        self.tried = np.zeros(self.batch_levels)
        order = np.repeat(np.arange(self.batch_levels), self.rollouts)
        self.rng.shuffle(order)
        self._queue = order.tolist()

    def learnability(self) -> np.ndarray:
        """p (1 - p) of each level of the batch from its rollouts so far."""
        p = np.divide(self.solved, self.tried, out=np.zeros_like(self.solved), where=self.tried > 0)
        return p * (1 - p)

    def next_task(self) -> Task:
        if self._pending is not None:
            raise RuntimeError("next_task() called twice without report() of the first task")
        if self.buffer and self.rng.random() < self.buffer_share:
            self._pending = -1
            return self.buffer[self.rng.integers(len(self.buffer))]
        self._pending = self._queue.pop()
        return self.batch[self._pending]

    def report(self, outcome: EpisodeOutcome) -> None:
        if self._pending is None:
            raise RuntimeError("report() of an episode that next_task() did not hand out")
        level, self._pending = self._pending, None
        if level < 0:
            return  # a buffer level: SFL scores levels only when fresh
        self.tried[level] += 1
        self.solved[level] += outcome.solved
        if not self._queue:  # the batch is scored: it replaces the buffer
            score = self.learnability()
            best = np.argsort(-score, kind="stable")[: self.buffer_size]
            self.buffer = [self.batch[i] for i in best if score[i] > 0]
            self.rebuilds += 1
            self._new_batch()
