"""Feedback curricula as orderings of C under the paper's hand-over rule (issue 42): the
curriculum chooses which task of C each episode starts from, by its own mechanism (solved tasks
stay in its levels: a level's score or success rate is what it learns from), and once every task
of C was solved at least once it is done, and every further episode is a target task, as in
Algorithms 1 and 2. So the paper's question, the order of the source tasks, is asked in
isolation from how much a curriculum trains on target tasks.

- ``plr_handover``: Prioritized Level Replay (plr.py) over C, scored by TD errors.
- ``learnability_handover``: the learnability sampler (learnability.py) over C.

Their values are the first study's (PLR's paper: beta = 0.1, rho = 0.1; SFL: rho = 0.5, K = 10
of the 100 levels, a window of 10 episodes).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from mediated_transfer.transfer import EpisodeOutcome, StrategyContext

from .learnability import Learnability
from .level_sets import LevelSet
from .plr import PrioritizedLevelReplay
from .plr_annulus import replace_levels


class PLRHandover(PrioritizedLevelReplay):
    """``strategy=plr_handover`` (conf/strategy/plr_handover.yaml)."""

    def __init__(self, context: StrategyContext, *, temperature: float, staleness: float):
        levels = LevelSet.of_c(context, "plr_handover")  # an empty C refused by this strategy's name
        super().__init__(context, temperature=temperature, staleness=staleness)
        replace_levels(self, levels)

    @property
    def done(self) -> bool:
        return self.levels.c_solved

    def report(self, outcome: EpisodeOutcome) -> None:
        if outcome.task is not None:  # a target task once done: nothing to score
            super().report(outcome)


class LearnabilityHandover(Learnability):
    """``strategy=learnability_handover`` (conf/strategy/learnability_handover.yaml)."""

    def __init__(self, context: StrategyContext, *, buffer_size: int, buffer_share: float, window: int):
        levels = LevelSet.of_c(context, "learnability_handover")  # an empty C refused by this strategy's name
        super().__init__(context, buffer_size=buffer_size, buffer_share=buffer_share, window=window)
        self.levels = levels
        self.history = [deque(maxlen=window) for _ in range(self.levels.count)]
        self.successes = np.zeros(self.levels.count)
        self.tries = np.zeros(self.levels.count)

    @property
    def done(self) -> bool:
        return self.levels.c_solved

    def report(self, outcome: EpisodeOutcome) -> None:
        if outcome.task is not None:
            super().report(outcome)
