"""Transfer strategies: which source task the next episode learns, until the source set C is
solved and learning continues on the target task.

A strategy has one job: choose the next source task and hear whether the agent solved it.
Before every episode ``next_task()`` is asked: a Task means "learn this source task", None
means "source phase over, learn the target task" (and stays None). After a source episode
``report(solved)`` is called; target episodes are not reported. Learning never stops between
the phases: the strategy only decides which task an episode starts from. ``start_episode`` and
``report_episode`` below are that protocol, shared by the experiment loop (run.py) and the
Gymnasium wrapper (wrapper.py), so both drive a strategy the same way.

- ``none``: no source phase (the paper's "without transfer", N_source = 0).
- ``regular`` (Algorithm 1, Strategy 1): a uniformly random task of C; removed when solved.
- ``scaffolded`` (Algorithm 2, Strategy 2): while nothing is solved, a random task of C;
  then a random solved task k and the unsolved task most similar to k by the cosine
  similarity of their sensor vectors (eq. 3). Solved tasks move from C to C_solved.
"""

from __future__ import annotations

import os
from typing import Any, Protocol, Sequence, runtime_checkable

import numpy as np

from ..env.task import Task

STRATEGIES = ("none", "regular", "scaffolded")


@runtime_checkable
class TransferStrategy(Protocol):
    name: str

    def next_task(self) -> Task | None:
        """The source task of the next episode; None once C is empty (target-task phase)."""

    def report(self, solved: bool) -> None:
        """Outcome of the episode on the task ``next_task`` returned last."""

    @property
    def in_source_phase(self) -> bool:
        """True while unsolved source tasks remain."""

    @property
    def solved_count(self) -> int:
        """Source tasks solved so far (|C_solved|)."""


class _SourcePhase:
    """Book-keeping shared by the strategies: C as a list of task indices, the pending task."""

    name = ""

    def __init__(self, tasks: Sequence[Task], rng: np.random.Generator):
        if not isinstance(rng, np.random.Generator):
            raise TypeError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
        self.tasks = list(tasks)
        self.rng = rng
        # Unsolved task indices in ascending order: C. A list, because removal happens once
        # per solved task while sampling happens every episode.
        self._unsolved = list(range(len(self.tasks)))
        self._pending: int | None = None
        # C lives in the process that made it: a copy in another process (a subprocess vector
        # env's worker) would run a curriculum of its own. TransferWrapper refuses that.
        self.owner_pid = os.getpid()

    @property
    def n_source(self) -> int:
        return len(self.tasks)

    @property
    def in_source_phase(self) -> bool:
        return bool(self._unsolved)

    @property
    def solved_count(self) -> int:
        return self.n_source - len(self._unsolved)

    @property
    def remaining(self) -> int:
        """|C|: source tasks still to solve."""
        return len(self._unsolved)

    def next_task(self) -> Task | None:
        if self._pending is not None:
            raise RuntimeError(
                f"{self.name}: next_task() called twice without report() on the first task"
            )
        if not self._unsolved:
            return None
        self._pending = self._choose()
        return self.tasks[self._pending]

    def report(self, solved: bool) -> None:
        if self._pending is None:
            raise RuntimeError(
                f"{self.name}: report() without a pending source task (target-task episodes "
                "are not reported)"
            )
        index, self._pending = self._pending, None
        if solved:
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
    in_source_phase = False
    solved_count = 0
    remaining = 0
    n_source = 0

    def next_task(self) -> None:
        return None

    def report(self, solved: bool) -> None:
        raise RuntimeError("none: report() without a pending source task (no source phase)")


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

    def __init__(self, tasks: Sequence[Task], sensors, rng: np.random.Generator):
        super().__init__(tasks, rng)
        sensors = np.asarray(sensors, dtype=float)
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


def start_episode(env, strategy: TransferStrategy, seed: int | None = None) -> tuple[Any, dict, Task | None]:
    """Reset ``env`` (a target-scenario MediatedInteractionEnv, possibly wrapped) to the episode
    ``strategy`` chooses: its next source task, or, once C is empty, a target task that ``env``
    samples from its own seeded generator. Returns (observation, info, task); task is None for
    a target-task episode."""
    task = strategy.next_task()
    observation, info = env.reset(seed=seed, options=None if task is None else {"task": task})
    return observation, info, task


def report_episode(strategy: TransferStrategy, task: Task | None, solved: bool) -> None:
    """Tell ``strategy`` whether the episode that ``start_episode`` began on ``task`` solved
    it; a target-task episode (task None) is not reported."""
    if task is not None:
        strategy.report(solved=solved)


def make_strategy(
    name: str,
    tasks: Sequence[Task],
    sensors=None,
    rng: np.random.Generator | None = None,
) -> TransferStrategy:
    """The strategy called ``name`` over the source task set ``tasks``.

    ``none`` needs an empty task set (N_source = 0); ``regular`` and ``scaffolded`` need a
    non-empty one (N_source >= 1), because a transfer strategy without source tasks would
    silently be the no-transfer baseline under another name. ``scaffolded`` needs ``sensors``
    (N_source x 11 sensor vectors); both random strategies need ``rng``.
    """
    if name not in STRATEGIES:
        raise ValueError(f"unknown strategy {name!r}; allowed: {', '.join(STRATEGIES)}")
    tasks = list(tasks)
    if name == "none":
        if tasks:
            raise ValueError(
                f"strategy 'none' has no source phase but got {len(tasks)} source tasks; "
                "use n_source=0 with strategy=none, or strategy=regular / scaffolded"
            )
        return NoTransfer()
    if not tasks:
        raise ValueError(
            f"strategy {name!r} needs source tasks: n_source must be >= 1, got 0 "
            "(use strategy=none for learning without transfer)"
        )
    if rng is None:
        raise ValueError(f"strategy {name!r} samples source tasks: pass rng")
    if name == "regular":
        return RegularTransfer(tasks, rng)
    if sensors is None:
        raise ValueError("strategy 'scaffolded' compares sensor vectors (eq. 3): pass sensors")
    return ScaffoldedTransfer(tasks, sensors, rng)
