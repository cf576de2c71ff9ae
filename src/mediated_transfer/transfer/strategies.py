"""The paper's transfer strategies: which source task the next episode learns, until the source
set C is solved and learning continues on the target task. They come through the same door as
a user's strategy (transfer/strategy.py, conf/strategy/*.yaml).

- ``none``: no source phase (the paper's "without transfer", N_source = 0).
- ``regular`` (Algorithm 1, Strategy 1): a uniformly random task of C; removed when solved.
- ``scaffolded`` (Algorithm 2, Strategy 2): while nothing is solved, a random task of C;
  then a random solved task k and the unsolved task most similar to k by the cosine
  similarity of their sensor vectors (eq. 3). Solved tasks move from C to C_solved.

Each is done once C is empty; target-task episodes' outcomes change nothing. Each accepts several
episodes in flight (``max_in_flight``, set by a loop of several environments).
"""

from __future__ import annotations

import os

import numpy as np

from ..env.task import Task
from .strategy import EpisodeOutcome, StrategyContext


class _SourcePhase:
    """Book-keeping shared by the strategies: C as a list of task indices, the pending task."""

    name = ""
    source_tasks = "required"  # a transfer strategy without C would be "none" under another name
    max_in_flight = 1
    """Episodes handed out (``next_task``) and not yet reported that the strategy accepts: 1 for
    a loop of one episode at a time; a loop of K environments (run_sb3.py, ``algorithm.n_envs``)
    sets K. Each report then names its episode by its task (``outcome.task``); a task solved in
    one episode leaves C once, whichever other episode of it is still in flight."""

    def __init__(self, context: StrategyContext):
        rng = context.rng
        if not isinstance(rng, np.random.Generator):
            raise TypeError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
        self.tasks = list(context.source_tasks)
        if not self.tasks:
            raise ValueError(f"strategy {self.name!r} needs source tasks: n_source must be >= 1, got 0 "
                             "(use strategy=none for learning without transfer)")
        self.rng = rng
        # Unsolved task indices in ascending order: C. A list, because removal happens once
        # per solved task while sampling happens every episode.
        self._unsolved = list(range(len(self.tasks)))
        self._pending: list[int] = []
        """Tasks handed out and not yet reported, in the order handed out."""
        # C lives in the process that made it: a copy in another process (a subprocess vector
        # env's worker) would run a curriculum of its own. TransferWrapper refuses that.
        self.owner_pid = os.getpid()

    @property
    def n_source(self) -> int:
        return len(self.tasks)

    @property
    def done(self) -> bool:
        """C is empty: the target task from now on."""
        return not self._unsolved

    @property
    def solved_count(self) -> int:
        return self.n_source - len(self._unsolved)

    @property
    def remaining(self) -> int:
        """|C|: source tasks still to solve."""
        return len(self._unsolved)

    def next_task(self) -> Task | None:
        if len(self._pending) >= self.max_in_flight:
            raise RuntimeError(
                f"{self.name}: next_task() called twice without report() on the first task"
                if self.max_in_flight == 1 else
                f"{self.name}: next_task() with {len(self._pending)} episodes in flight (max_in_flight)"
            )
        if not self._unsolved:
            return None
        index = self._choose()
        self._pending.append(index)
        return self.tasks[index]

    def report(self, outcome: EpisodeOutcome) -> None:
        if outcome.task is None:  # a target-task episode: C does not change
            return
        pending = self._pending
        # One in flight: it is that one (as a loop of one episode at a time has always reported).
        at = 0 if len(pending) == 1 else next(
            (j for j, i in enumerate(pending) if self.tasks[i] is outcome.task), None)
        if at is None:
            raise RuntimeError(f"{self.name}: report() of a source task that next_task() did not hand out")
        index = pending.pop(at)
        # Solved once: with several episodes in flight, two may have learned the same task.
        if outcome.solved and index in self._unsolved:
            self._unsolved.remove(index)
            self._solved(index)

    def _choose(self) -> int:
        raise NotImplementedError

    def _solved(self, index: int) -> None:
        """Hook: a task just moved from C to C_solved."""


class NoTransfer:
    """``strategy=none`` (conf/strategy/none.yaml). No source phase: every episode learns the
    target task."""

    name = "none"
    source_tasks = "none"
    max_in_flight = 1
    """Any number of target-task episodes may be in flight (a loop of K environments sets K)."""
    done = True
    solved_count = 0
    remaining = 0
    n_source = 0

    def __init__(self, context: StrategyContext | None = None):
        if context is not None and context.n_source:
            raise ValueError(f"strategy 'none' has no source phase but got {context.n_source} source tasks; "
                             "use n_source=0 with strategy=none, or strategy=regular / scaffolded")

    def next_task(self) -> None:
        return None

    def report(self, outcome: EpisodeOutcome) -> None:
        if outcome.task is not None:
            raise RuntimeError("none: report() of a source task (no source phase)")


class RegularTransfer(_SourcePhase):
    """``strategy=regular`` (conf/strategy/regular.yaml). Algorithm 1: a uniformly random task
    from C each episode, removed from C when solved."""

    name = "regular"

    def _choose(self) -> int:
        return self._unsolved[int(self.rng.integers(len(self._unsolved)))]


class ScaffoldedTransfer(_SourcePhase):
    """``strategy=scaffolded`` (conf/strategy/scaffolded.yaml). Algorithm 2: the unsolved task
    most cosine-similar (eq. 3) to a random solved one.

    Ties in similarity go to the lowest task index. ``sensors`` holds the tasks' sensor
    vectors s, one row per task, in the order of ``tasks``.
    """

    name = "scaffolded"

    def __init__(self, context: StrategyContext):
        super().__init__(context)
        sensors = np.asarray(context.sensors, dtype=float)
        if sensors.ndim != 2 or sensors.shape[0] != self.n_source:
            raise ValueError(
                f"sensors must have one row per source task ({self.n_source}), got shape "
                f"{sensors.shape}"
            )
        norms = np.linalg.norm(sensors, axis=1)
        if not np.all(np.isfinite(norms)) or np.any(norms == 0):
            raise ValueError("sensors must be finite and non-zero (eq. 3 divides by |s|)")
        # Unit rows: the cosine similarity of two tasks is then one dot product, and a whole
        # row of similarities one matrix-vector product per episode.
        self._unit = sensors / norms[:, None]
        self._solved_mask = np.zeros(self.n_source, dtype=bool)
        self._solved_list: list[int] = []
        self._similarity = np.empty(self.n_source)

    def _choose(self) -> int:
        if not self._solved_list:
            return self._unsolved[int(self.rng.integers(len(self._unsolved)))]
        k = self._solved_list[int(self.rng.integers(len(self._solved_list)))]
        return self.most_similar_unsolved(k)

    def most_similar_unsolved(self, k: int) -> int:
        """Index of the task in C (other than k) with the largest cosine similarity to task k."""
        np.dot(self._unit, self._unit[k], out=self._similarity)
        self._similarity[self._solved_mask] = -np.inf
        self._similarity[k] = -np.inf
        return int(np.argmax(self._similarity))

    def _solved(self, index: int) -> None:
        self._solved_mask[index] = True
        self._solved_list.append(index)
