"""The paper's world as a world of the door (env/door.py): the option ``env=default`` and every
conf/env/*.yaml reading of it. It declares what the rest of the project reads from a world:
its config, sensor layout, actions, task space, environment and scripted policy."""

from __future__ import annotations

import numpy as np

from .config import WorldConfig
from .mediated_env import ACTION_NAMES, MediatedInteractionEnv
from .sensors import PAPER_SENSORS, Sensors
from .task import Task, check_room, sample_tasks, sensor_vectors
from .task_space import TaskSpace


class PaperWorld:
    """An agent with interaction radius 10, a disc target and an L-shaped mediator (Figure 1);
    the source tasks place the target within reach, the target tasks out of it."""

    config_class = WorldConfig
    """The dataclass of the ``env`` keys; the door builds it from the option's keys."""
    sensors: Sensors = PAPER_SENSORS
    action_names: tuple[str, ...] = ACTION_NAMES

    def __init__(self, config: WorldConfig = WorldConfig()):
        self.config = config

    @property
    def num_actions(self) -> int:
        return len(self.action_names)

    @property
    def task_space(self) -> TaskSpace:
        """What a task is and how tasks of each difficulty are drawn (curricula read it)."""
        return TaskSpace(self.config)

    def make_env(self, scenario: str = "target", render_mode: str | None = None):
        """A fresh environment of ``scenario`` ("source" or "target"); ``reset(options={"task": t})``
        starts any task of the task space."""
        return MediatedInteractionEnv(scenario, self.config, render_mode)

    def sample_tasks(self, scenario: str, n: int, rng: np.random.Generator) -> list:
        """``n`` random tasks of ``scenario``, drawn from ``rng`` (evaluation, source pools)."""
        return sample_tasks(scenario, n, rng, self.config)

    def task_sensors(self, tasks) -> np.ndarray:
        """The sensor vector of each task at its start (eq. 2, O active), one row per task: what
        the source task set C is clustered on and the scaffolded strategy's eq. (3) compares."""
        return sensor_vectors(tasks, self.config)

    def task_from_coordinates(self, coordinates) -> Task:
        """A task from its flat ``coordinates`` (how source task sets are cached)."""
        return Task.from_coordinates(coordinates)

    def check_room(self, scenario: str) -> None:
        """ValueError (one line) if the config's sizes leave no room for tasks of ``scenario``."""
        check_room(scenario, self.config)

    def scripted_policy(self, env, seed: int):
        """A policy that solves the scenario of ``env`` (animate's ``--policy scripted``)."""
        from .scripted import ScriptedDirectPolicy, ScriptedToolPolicy

        return ScriptedToolPolicy(env) if env.unwrapped.scenario == "target" else ScriptedDirectPolicy(env)
