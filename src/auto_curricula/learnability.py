"""A success-based sampler over the levels C + {a target task}: learnability p (1 - p), after
Sampling For Learnability (SFL; Rutherford et al. 2024, "No Regrets"), the sampler Kinetix
(Matthews et al. 2025) trained its agents with.

SFL keeps a buffer of the K levels of highest learnability p (1 - p), p a level's success rate
under the current policy, and draws each episode's level from that buffer with probability rho,
otherwise from the level generator. Here the generator is a uniform draw over the levels, and p
is estimated from the level's own training episodes (its last ``window``), so the sampler spends
no extra environment steps on scoring (SFL rolls out N fresh levels every T updates, steps that
a budget of learning steps would not count). A level not yet tried has no p and is reached
through the uniform draws; a level at p = 0 or 1 has learnability 0 and leaves the buffer.

Values (conf/strategy/learnability.yaml): rho = 0.5 (SFL's buffer share), K = 10 (a tenth of
the 101 levels of N_source = 100; SFL keeps the top fraction of the levels it scored), window 10.
Never done: target tasks are one of its levels.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from mediated_transfer.transfer import EpisodeOutcome, StrategyContext

from .levels import Levels


class Learnability:
    """``strategy=learnability`` (conf/strategy/learnability.yaml)."""

    source_tasks = "required"
    done = False

    def __init__(self, context: StrategyContext, *, buffer_size: int, buffer_share: float, window: int):
        for key, value in (("buffer_size", buffer_size), ("window", window)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"strategy.{key} must be an integer >= 1, got {value!r}")
        if not isinstance(buffer_share, (int, float)) or not 0 <= buffer_share <= 1:
            raise ValueError(f"strategy.buffer_share must be a number in [0, 1], got {buffer_share!r}")
        self.rng = context.rng
        self.buffer_size, self.buffer_share = buffer_size, float(buffer_share)
        self.levels = Levels(context, "learnability")
        self.history = [deque(maxlen=window) for _ in range(self.levels.count)]
        # Running successes and tries over each level's window: p for all levels in O(levels)
        # numpy work per episode, not a Python mean per level (the same numbers: sums of 0s and 1s).
        self.successes = np.zeros(self.levels.count)
        self.tries = np.zeros(self.levels.count)

    @property
    def solved_count(self) -> int:
        return self.levels.solved_count

    def learnability(self) -> np.ndarray:
        """p (1 - p) per level from its last episodes; 0 for a level not yet tried."""
        p = np.divide(self.successes, self.tries, out=np.zeros_like(self.successes), where=self.tries > 0)
        return p * (1 - p)

    def buffer(self) -> np.ndarray:
        """The (at most) ``buffer_size`` levels of highest learnability > 0 (ties: lower index)."""
        score = self.learnability()
        best = np.argsort(-score, kind="stable")[: self.buffer_size]
        return best[score[best] > 0]

    def next_task(self):
        buffer = self.buffer()
        if len(buffer) and self.rng.random() < self.buffer_share:
            index = int(buffer[self.rng.integers(len(buffer))])
        else:
            index = int(self.rng.integers(self.levels.count))
        return self.levels.hand_out(index)

    def report(self, outcome: EpisodeOutcome) -> None:
        level = self.levels.take(outcome)
        history, solved = self.history[level], float(outcome.solved)
        if len(history) == history.maxlen:
            self.successes[level] -= history[0]
            self.tries[level] -= 1
        history.append(solved)
        self.successes[level] += solved
        self.tries[level] += 1
