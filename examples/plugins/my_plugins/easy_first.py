"""An "easy-first" curriculum: the unsolved source task whose target is nearest the goal.

Selected like a built-in, once this folder is on the config search path and the package on
PYTHONPATH (docs/extending.md):

    python -m mediated_transfer strategy=easy_first n_source=15 \
        hydra.searchpath=[pkg://my_plugins.conf]
"""

from __future__ import annotations

from mediated_transfer.transfer import EpisodeOutcome, StrategyContext


class EasyFirst:
    """Source tasks of C in order of their target's distance to the goal (at O), nearest first;
    a task stays until it is solved, or for at most ``max_attempts`` episodes (0: no limit),
    then goes to the back of the queue. Done once every task is solved."""

    source_tasks = "required"  # needs N_source >= 1

    def __init__(self, context: StrategyContext, max_attempts: int = 0):
        if isinstance(max_attempts, bool) or not isinstance(max_attempts, int) or max_attempts < 0:
            raise ValueError(f"strategy.max_attempts must be an integer >= 0, got {max_attempts!r}")
        self.tasks = context.source_tasks
        self.queue = sorted(range(len(self.tasks)), key=lambda i: self.tasks[i].target_distance)
        self.max_attempts = max_attempts
        self.attempts = 0
        self.solved_count = 0

    def next_task(self):
        return self.tasks[self.queue[0]]

    def report(self, outcome: EpisodeOutcome) -> None:
        if outcome.task is None:  # a target-task episode
            return
        self.attempts += 1
        if outcome.solved:
            self.queue.pop(0)
            self.solved_count += 1
            self.attempts = 0
        elif self.max_attempts and self.attempts >= self.max_attempts:
            self.queue.append(self.queue.pop(0))
            self.attempts = 0

    @property
    def done(self) -> bool:
        return not self.queue
