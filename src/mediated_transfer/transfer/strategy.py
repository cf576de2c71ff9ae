"""What a transfer strategy (a curriculum) is: the door every strategy comes through, the
paper's and a user's alike.

A strategy is chosen by config: ``conf/strategy/<name>.yaml`` holds its ``_target_`` (a class or
function, by dotted path), its ``name`` (table rows, folders, MLflow) and its own parameters.
The run loop calls ``_target_(context=StrategyContext, **parameters)`` once per run, then:

- before every episode, while the strategy is not ``done``: ``next_task()``. A Task means "this
  episode starts from this task" (a source task of C, or any task of the run's world's task space,
  ``context.task_space``, the world's ``task_space``: env/door.py); None means "a target task", which the environment samples from its
  own seeded stream. Once ``done`` is true, every further episode is a target task.
- after every episode, source or target: ``report(EpisodeOutcome)``: the task (None for a
  target task), whether it was solved, its return and length, the learning step, and the
  learner's signals the strategy asked for (``signals = ("td_error",)``: the episode's mean
  absolute TD error, from learners that offer ``td_error``).

Optional attributes: ``solved_count`` (source tasks solved, recorded in result.json),
``source_tasks`` ("required": N_source >= 1, "none": N_source = 0, "optional", the default),
``signals`` and ``max_in_flight`` (settable; a strategy that has it accepts that many episodes
handed out and not yet reported, each report naming its episode by ``outcome.task``: a loop of
K environments, PPO's ``algorithm.n_envs``, sets it to K; one without it runs one at a time). Learning never stops between the phases: a strategy only decides which task
each episode starts from.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any, Callable, Protocol, runtime_checkable

import numpy as np

from ..env.config import WorldConfig
from ..env.task import Task
from ..env.task_space import TaskSpace

SOURCE_TASKS = ("required", "none", "optional")
"""What a strategy needs of C (its ``source_tasks`` attribute): N_source >= 1, 0, or either."""
SIGNALS = ("td_error",)
"""Learner signals a strategy may ask for (its ``signals`` attribute)."""
METHODS = ("next_task", "report", "done")
"""What every strategy has (the interface checked before a run)."""


@dataclass(frozen=True)
class EpisodeOutcome:
    """How one episode went, as the strategy hears it."""

    task: Task | None
    """The task ``next_task`` returned for it; None: a target task."""
    solved: bool
    """The episode ended in the goal (terminated), not at the step limit."""
    episode_return: float
    length: int
    """Steps of the episode."""
    step: int
    """Learning steps of the run so far, this episode's included."""
    td_error: float | None = None
    """Mean absolute TD error of the episode's transitions; None unless asked for (``signals``)."""


@dataclass
class StrategyContext:
    """What a strategy is built from: its random stream, the world's config and its task space
    (the run's world's, env/door.py), and the clustered source task set C (built when first
    asked for, and cached)."""

    rng: np.random.Generator
    """The strategy's own stream (from the run's seed; no other part of the run draws from it)."""
    world: WorldConfig = field(default_factory=WorldConfig)
    n_source: int = 0
    """N_source: size of C."""
    build_source_tasks: Callable[[], list[Task]] | None = None
    """Makes C (clustering is costly: only strategies that use C pay for it)."""
    given_sensors: np.ndarray | None = None
    """Sensor vectors to use instead of C's own (tests of eq. 3 on chosen vectors)."""
    task_space: Any = None
    """The run's world's task space (``world.task_space``, env/door.py): what curricula move
    over; None: the paper's (``TaskSpace(world)``)."""
    task_sensors: Callable[[list], np.ndarray] | None = None
    """The run's world's sensor vectors of tasks (source_tasks.task_sensors): what C is
    clustered on and eq. (3) compares; None: the paper's eq. (2)."""

    def __post_init__(self) -> None:
        if self.task_space is None:
            self.task_space = TaskSpace(self.world)

    @classmethod
    def of_tasks(cls, tasks, rng: np.random.Generator, world=None, sensors=None) -> "StrategyContext":
        """A context with a given C (tests, the Gymnasium wrapper used from Python). ``world``:
        a world (env/door.py; its config and task space), a WorldConfig (the paper's world of
        it), or None (the paper's)."""
        tasks = list(tasks)
        from ..env.door import as_world
        from .source_tasks import task_sensors

        world = as_world(world)
        return cls(rng=rng, world=world.config, n_source=len(tasks), build_source_tasks=lambda: tasks,
                   given_sensors=sensors, task_space=world.task_space,
                   task_sensors=functools.partial(task_sensors, world))

    @functools.cached_property
    def source_tasks(self) -> list[Task]:
        """C: N_source source tasks, one per cluster (Sec. V)."""
        return [] if self.build_source_tasks is None else list(self.build_source_tasks())

    @functools.cached_property
    def sensors(self) -> np.ndarray:
        """The sensor vectors s of C, one row per task (eq. 2, or the world's own)."""
        from .source_tasks import sensor_vectors

        if self.given_sensors is not None:
            return np.asarray(self.given_sensors, dtype=float)
        if self.task_sensors is not None:
            return np.asarray(self.task_sensors(self.source_tasks), dtype=float)
        return sensor_vectors(self.source_tasks, self.world)


@runtime_checkable
class Strategy(Protocol):
    def next_task(self) -> Task | None:
        """The task of the next episode; None: a target task."""

    def report(self, outcome: EpisodeOutcome) -> None:
        """How the episode that ``next_task`` (or, once done, the environment) began went."""

    @property
    def done(self) -> bool:
        """True once every further episode is a target task."""


def start_episode(env, strategy: Strategy, seed: int | None = None) -> tuple[Any, dict, Task | None]:
    """Reset ``env`` (a target-scenario MediatedInteractionEnv, possibly wrapped) to the episode
    ``strategy`` chooses: its next task, or, once it is done or returns None, a target task
    that ``env`` samples from its own seeded generator. Returns (observation, info, task)."""
    task = None if strategy.done else strategy.next_task()
    observation, info = env.reset(seed=seed, options=None if task is None else {"task": task})
    return observation, info, task


def make_strategy(name: str, tasks=(), sensors=None, rng: np.random.Generator | None = None,
                  world=None, **params) -> Strategy:
    """The strategy option ``name`` (conf/strategy/<name>.yaml, or a plugin's on the config
    search path) over the source task set ``tasks``, from Python (the run loop builds its own).
    ``world``: a world (env/door.py), whose task space curricula move over; a WorldConfig or
    None: the paper's world."""
    from .. import plugins
    from ..config.targets import builtin_target

    try:
        target = builtin_target("strategy", name)
    except KeyError as error:
        raise ValueError(error.args[0]) from None
    context = StrategyContext.of_tasks(tasks, rng if rng is not None else np.random.default_rng(), world, sensors)
    return plugins.call(plugins.locate("strategy", target), params, context=context)


def wants_td_error(strategy: Strategy) -> bool:
    return "td_error" in tuple(getattr(strategy, "signals", ()) or ())


def solved_count(strategy: Strategy) -> int:
    return int(getattr(strategy, "solved_count", 0))
