"""Level sets of issue 42's replay curricula, every level a fixed Task handed out as itself (so
that an annulus level counts as exposure to the target tasks whoever drew it):

- ``LevelSet.of_c``: the tasks of C only, for the orderings of C under the paper's hand-over
  rule (target tasks once every task of C was solved at least once);
- ``LevelSet.with_annulus``: C plus ``count`` fixed target tasks, drawn from a stream of their
  own, disjoint from the evaluation tasks' (which come from each run's seed), and the same for
  every run, as PLR's Procgen training levels are a fixed set of the test generator's seeds.

The first study's ``Levels`` (levels.py: C plus one "target task" level) stays as its runs
computed it.
"""

from __future__ import annotations

import numpy as np

from mediated_transfer.env import Task
from mediated_transfer.transfer import EpisodeOutcome, StrategyContext

ANNULUS_STREAM = 42
"""Second word of the annulus levels' seed sequence: [level_seed, 42] is no run's stream (a run
derives its streams from [seed, 1..5])."""


class LevelSet:
    def __init__(self, tasks: list[Task], sources: int):
        self.tasks, self.sources = tasks, sources
        self.count = len(tasks)
        self.solved = [False] * sources
        self._pending: int | None = None

    @classmethod
    def of_c(cls, context: StrategyContext, name: str) -> "LevelSet":
        tasks = list(context.source_tasks)
        if not tasks:
            raise ValueError(f"strategy {name!r} orders the tasks of C: n_source must be >= 1, got 0")
        return cls(tasks, len(tasks))

    @classmethod
    def with_annulus(cls, context: StrategyContext, name: str, count: int, level_seed: int) -> "LevelSet":
        levels = cls.of_c(context, name)
        rng = np.random.default_rng(np.random.SeedSequence([level_seed, ANNULUS_STREAM]))
        space = context.task_space
        return cls(levels.tasks + [space.sample_scenario("target", rng) for _ in range(count)], levels.sources)

    def hand_out(self, index: int) -> Task:
        """The task of level ``index``, remembered until its report."""
        if self._pending is not None:
            raise RuntimeError("next_task() called twice without report() of the first task")
        self._pending = index
        return self.tasks[index]

    def take(self, outcome: EpisodeOutcome) -> int:
        """The level the reported episode was handed out from; a solved task of C is marked."""
        if self._pending is None:
            raise RuntimeError("report() of an episode that next_task() did not hand out")
        index, self._pending = self._pending, None
        if index < self.sources and outcome.solved:
            self.solved[index] = True
        return index

    @property
    def solved_count(self) -> int:
        """Tasks of C solved at least once."""
        return sum(self.solved)

    @property
    def c_solved(self) -> bool:
        """Every task of C solved at least once: the paper's moment to hand over."""
        return all(self.solved)
