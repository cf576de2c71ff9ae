"""A reverse curriculum after Florensa et al. 2017 ("Reverse Curriculum Generation for
Reinforcement Learning", Algorithm 1 and Procedure 2), over the target's distance from O.

Their loop, per iteration: starts <- SampleNearby(seeds, N_new), plus N_old starts replayed
from starts_old; train on them; keep the starts whose success rate R lies in [R_min, R_max]
("good starts": neither mastered nor hopeless); add them to starts_old. SampleNearby
(Procedure 2) runs short noisy rollouts (a Brownian motion) from the seeds, collects every state
they visit, and draws the N_new new starts from that collection. starts_old begins as the goal.

Here a start is a target distance (a task at that distance, uniform angle, the tool in reach),
the goal the nearest distance of the task space, and a rollout a random walk of ``walk_steps``
normal steps of ``step_std`` over the distance, reflected at the task space's ends (the agent's
actions cannot carry a target beyond its reach, so the walk is over the task parameter, not
through the world). The collection holds ``pool`` visited distances. Kept from the paper (values
in conf/strategy/reverse.yaml): R_min = 0.1, R_max = 0.9, N_new : N_old = 2 : 1, starts_old
seeded with the goal. Scaled to this world's budget: 10 new and 5 old starts per iteration, each
tried ``rollouts`` = 5 times.

Seeds of the next iteration: the good starts among this iteration's *new* starts. Replayed old
starts keep forgetting away (their purpose in the paper); they are not seeds, or a replayed goal,
always mastered, would pull the frontier back to it. Where no new start is good, the next
iteration grows from the new starts that were mastered (R > R_max), else from the previous seeds
(the paper keeps the previous ones, which here would never leave a goal mastered at once). Done,
and target tasks from then on, once a start in the target annulus reaches R >= R_min.

The first study's version (issue 42) seeded from the replayed old starts too, so a third of the
seeds snapped back to the goal every iteration; a learner that solves every task needed a median
321 iterations (20-3013, seeds 0-99) to reach the annulus; this version needs 18 (5-66).
tests/test_curricula.py bounds that now.
"""

from __future__ import annotations

import numpy as np

from mediated_transfer.transfer import EpisodeOutcome, StrategyContext


class ReverseCurriculum:
    """``strategy=reverse`` (conf/strategy/reverse.yaml)."""

    source_tasks = "none"  # starts are made from the task space: n_source=0
    done = False  # until a start in the target annulus reaches r_min

    def __init__(self, context: StrategyContext, *, r_min: float, r_max: float, new_starts: int,
                 old_starts: int, rollouts: int, walk_steps: int, step_std: float, pool: int):
        if not 0.0 <= r_min <= r_max <= 1.0:
            raise ValueError(f"strategy.r_min and strategy.r_max must satisfy 0 <= r_min <= r_max <= 1, "
                             f"got {r_min!r} and {r_max!r}")
        for key, value in (("new_starts", new_starts), ("rollouts", rollouts), ("walk_steps", walk_steps),
                           ("pool", pool)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"strategy.{key} must be an integer >= 1, got {value!r}")
        if isinstance(old_starts, bool) or not isinstance(old_starts, int) or old_starts < 0:
            raise ValueError(f"strategy.old_starts must be an integer >= 0, got {old_starts!r}")
        if not isinstance(step_std, (int, float)) or not 0 < step_std < 1e6:
            raise ValueError(f"strategy.step_std must be a number > 0, got {step_std!r}")
        self.rng, self.space = context.rng, context.task_space
        self.r_min, self.r_max = r_min, r_max
        self.new_starts, self.old_starts, self.rollouts = new_starts, old_starts, rollouts
        self.walk_steps, self.step_std, self.pool = walk_steps, float(step_std), pool
        self.low, self.high = self.space.distances
        self.target_from = self.space.target_distances[0]
        self.seeds: list[float] = [self.low]  # the goal: SampleNearby's first input
        self.good: list[float] = []  # the last iteration's good starts (new and replayed)
        self.old: list[float] = [self.low]  # starts_old, seeded with the goal as in the paper
        self.iterations = 0
        self._queue: list[int] = []  # indices of the starts still to roll out, one per episode
        self._starts: list[float] = []
        self._tried: np.ndarray = np.zeros(0)
        self._solved: np.ndarray = np.zeros(0)
        self._pending: int | None = None
        self._begin_iteration()

    def _reflect(self, x: np.ndarray) -> np.ndarray:
        """Fold ``x`` into [low, high] (a reflecting wall: clipping would pile starts on the ends)."""
        width = self.high - self.low
        folded = np.mod(x - self.low, 2 * width)
        return self.low + np.where(folded > width, 2 * width - folded, folded)

    def sample_nearby(self, seeds: list[float], n: int) -> list[float]:
        """Procedure 2: random walks of ``walk_steps`` steps from seeds drawn uniformly, until
        ``pool`` visited distances are collected; ``n`` of them drawn uniformly."""
        walks = -(-self.pool // self.walk_steps)
        position = np.asarray(seeds, dtype=float)[self.rng.integers(len(seeds), size=walks)]
        visited = []
        for _ in range(self.walk_steps):
            position = self._reflect(position + self.rng.normal(0.0, self.step_std, size=walks))
            visited.append(position)
        collection = np.concatenate(visited)[: self.pool]
        return collection[self.rng.integers(len(collection), size=n)].tolist()

    def _begin_iteration(self) -> None:
        starts = self.sample_nearby(self.seeds, self.new_starts)
        if self.old_starts:
            starts += [self.old[i] for i in self.rng.integers(len(self.old), size=self.old_starts)]
        self._starts = starts
        self._tried, self._solved = np.zeros(len(starts)), np.zeros(len(starts))
        order = [i for i in range(len(starts)) for _ in range(self.rollouts)]
        self.rng.shuffle(order)
        self._queue = order

    def next_task(self):
        self._pending = self._queue.pop()
        return self.space.sample(self.rng, self._starts[self._pending])

    def report(self, outcome: EpisodeOutcome) -> None:
        if outcome.task is None or self._pending is None:  # a target task (once done)
            return
        index, self._pending = self._pending, None
        self._tried[index] += 1
        self._solved[index] += outcome.solved
        if not self._queue:
            self._end_iteration()

    def _end_iteration(self) -> None:
        rates = self._solved / self._tried
        starts = np.asarray(self._starts)
        in_band = (rates >= self.r_min) & (rates <= self.r_max)
        new = np.arange(len(starts)) < self.new_starts
        self.iterations += 1
        if np.any((starts >= self.target_from) & (rates >= self.r_min)):
            self.done = True  # the frontier reached the target tasks
            return
        self.good = starts[in_band].tolist()
        self.old += self.good
        self.seeds = starts[in_band & new].tolist() or starts[(rates > self.r_max) & new].tolist() or self.seeds
        self._begin_iteration()
