"""A reverse curriculum after Florensa et al. 2017 ("Reverse Curriculum Generation for
Reinforcement Learning", Algorithm 1), over the target's distance from O.

Their loop, per iteration: starts <- SampleNearby(starts, N_new), plus N_old starts replayed
from starts_old; train on them; keep the starts whose success rate R lies in [R_min, R_max]
("good starts": neither mastered nor hopeless); add them to starts_old. SampleNearby is a
Brownian motion from the good starts. The first start is the goal itself.

Here a start is a target distance (a task at that distance, uniform angle, the tool in reach),
the first one the nearest source distance, and the Brownian motion moves the distance. Kept from
the paper (values in conf/strategy/reverse.yaml): R_min = 0.1, R_max = 0.9 and
N_new : N_old = 2 : 1 (200 : 100). Scaled to this
world's budget (a few thousand episodes a run, where they trained on 300 starts an iteration):
``new_starts`` 10 and ``old_starts`` 5 per iteration, each tried ``rollouts`` 5 times (R then
takes the values 0, 0.2, ..., 1, of which 0.2-0.8 are in the band), and the Brownian motion's
displacement over one iteration normal with ``brownian_std`` 1 (the agent's move length).
Where an iteration leaves no good start, the next grows from its mastered starts (R > R_max)
if any, else from the previous good starts: the paper keeps the previous good starts, which
here would never leave a goal that is mastered at once. Done, and target tasks from then on,
once a start in the target annulus reaches R >= R_min.
"""

from __future__ import annotations

import numpy as np

from mediated_transfer.transfer import EpisodeOutcome, StrategyContext


class ReverseCurriculum:
    """``strategy=reverse`` (conf/strategy/reverse.yaml)."""

    source_tasks = "none"  # starts are made from the task space: n_source=0
    done = False  # until a start in the target annulus reaches r_min

    def __init__(self, context: StrategyContext, *, r_min: float, r_max: float, new_starts: int,
                 old_starts: int, rollouts: int, brownian_std: float):
        if not 0.0 <= r_min <= r_max <= 1.0:
            raise ValueError(f"strategy.r_min and strategy.r_max must satisfy 0 <= r_min <= r_max <= 1, "
                             f"got {r_min!r} and {r_max!r}")
        for key, value in (("new_starts", new_starts), ("rollouts", rollouts)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"strategy.{key} must be an integer >= 1, got {value!r}")
        if isinstance(old_starts, bool) or not isinstance(old_starts, int) or old_starts < 0:
            raise ValueError(f"strategy.old_starts must be an integer >= 0, got {old_starts!r}")
        if not isinstance(brownian_std, (int, float)) or not 0 < brownian_std < 1e6:
            raise ValueError(f"strategy.brownian_std must be a number > 0, got {brownian_std!r}")
        self.rng, self.space = context.rng, context.task_space
        self.r_min, self.r_max = r_min, r_max
        self.new_starts, self.old_starts, self.rollouts = new_starts, old_starts, rollouts
        self.brownian_std = float(brownian_std)
        self.low, self.high = self.space.distances
        self.target_from = self.space.target_distances[0]
        self.good: list[float] = [self.low]  # the goal's neighbourhood: the first start
        self.old: list[float] = [self.low]
        self.iterations = 0
        self._queue: list[int] = []  # indices of the starts still to roll out, one per episode
        self._starts: list[float] = []
        self._tried: np.ndarray = np.zeros(0)
        self._solved: np.ndarray = np.zeros(0)
        self._pending: int | None = None
        self._begin_iteration()

    def sample_nearby(self, seeds: list[float], n: int) -> list[float]:
        """``n`` starts, each a Brownian displacement of a random seed start, reflected at the task
        space's ends (clipping would pile starts up on the goal's edge)."""
        origins = np.asarray(seeds)[self.rng.integers(len(seeds), size=n)]
        moved = origins + self.rng.normal(0.0, self.brownian_std, size=n)
        width = self.high - self.low
        folded = np.mod(moved - self.low, 2 * width)  # a reflecting walk on [low, high]
        return (self.low + np.where(folded > width, 2 * width - folded, folded)).tolist()

    def _begin_iteration(self) -> None:
        starts = self.sample_nearby(self.good, self.new_starts)
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
        good = starts[in_band].tolist()
        mastered = starts[rates > self.r_max].tolist()
        self.iterations += 1
        if np.any((starts >= self.target_from) & (rates >= self.r_min)):
            self.done = True  # the frontier reached the target tasks
            return
        self.old += good
        self.good = good or mastered or self.good
        self._begin_iteration()
