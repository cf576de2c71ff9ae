"""Domain randomisation: every episode a task whose target distance is uniform over the whole
task space, from the source tasks' nearest to the target annulus' farthest. No feedback."""

from __future__ import annotations

from mediated_transfer.transfer import EpisodeOutcome, StrategyContext


class DomainRandomisation:
    """``strategy=dr``. A distance in the target annulus starts a target task (the environment's
    own, so that target episodes count as such); any nearer one a task of the task space at that
    distance. Never done: the distribution does not change."""

    source_tasks = "none"  # needs no C: n_source=0
    done = False

    def __init__(self, context: StrategyContext):
        self.rng, self.space = context.rng, context.task_space
        self.low, self.high = self.space.distances
        self.target_from = self.space.target_distances[0]

    def next_task(self):
        distance = float(self.rng.uniform(self.low, self.high))
        return None if distance >= self.target_from else self.space.sample(self.rng, distance)

    def report(self, outcome: EpisodeOutcome) -> None:
        """Outcomes change nothing: domain randomisation has no feedback."""
