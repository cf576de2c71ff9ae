"""The levels a replay curriculum samples from: the tasks of C (by index) and, as the last
level, "a target task", handed out as None so that the environment samples it from its own
stream and the run counts it as a target-task episode."""

from __future__ import annotations

from mediated_transfer.transfer import EpisodeOutcome, StrategyContext


class Levels:
    def __init__(self, context: StrategyContext, name: str):
        self.tasks = list(context.source_tasks)
        if not self.tasks:
            raise ValueError(f"strategy {name!r} samples over C and the target task: n_source must be >= 1, got 0")
        self.target = len(self.tasks)
        self.count = self.target + 1
        self.solved = [False] * self.target
        self._pending: int | None = None

    def hand_out(self, index: int):
        """The task of level ``index`` (None: a target task); remembered until its report."""
        if self._pending is not None:
            raise RuntimeError("next_task() called twice without report() of the first task")
        self._pending = index
        return None if index == self.target else self.tasks[index]

    def take(self, outcome: EpisodeOutcome) -> int:
        """The level the reported episode was handed out from."""
        if self._pending is None:
            raise RuntimeError("report() of an episode that next_task() did not hand out")
        index, self._pending = self._pending, None
        if index < self.target and outcome.solved:
            self.solved[index] = True
        return index

    @property
    def solved_count(self) -> int:
        """Source tasks of C solved at least once."""
        return sum(self.solved)
