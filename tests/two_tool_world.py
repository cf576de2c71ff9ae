"""A test double of a world whose tasks hold two tools, only one of which can reach: enough of
the world door's contract (docs/extending.md) to run the one run loop end to end on tasks that
are not the paper's ``Task``. Not physics: a move pulls the target one unit towards O when the
held tool's hook reaches it. Tool A's hook reaches 4 beyond its corner, tool B's only 1."""

from __future__ import annotations

import math
from dataclasses import dataclass

import gymnasium
import numpy as np

from mediated_transfer.env import WorldConfig
from mediated_transfer.env.sensors import Sensors

HOOKS = (4.0, 1.0)
"""How far beyond its corner each tool's hook reaches: A's pulls a target from the annulus, B's
cannot."""


@dataclass(frozen=True)
class TwoToolTask:
    """The target's position and each tool's corner (x, y) and angle."""

    target_position: tuple[float, float]
    tools: tuple[tuple[float, float, float], ...]

    @property
    def coordinates(self) -> np.ndarray:
        return np.array([*self.target_position, *(v for tool in self.tools for v in tool)])

    @property
    def target_distance(self) -> float:
        return math.hypot(*self.target_position)


def _polar(rng, low: float, high: float) -> tuple[float, float]:
    r, phi = rng.uniform(low, high), rng.uniform(0, 2 * math.pi)
    return r * math.cos(phi), r * math.sin(phi)


class TwoToolWorld:
    config_class = WorldConfig
    sensors = Sensors(("AT", "BT", "AO", "BO"), ("target", "target", "origin", "origin"), ("A", "B", "T", "O"))
    action_names = ("pick A", "pick B", "pick T", "pick O", "move in")

    def __init__(self, config: WorldConfig = WorldConfig()):
        self.config = config

    @property
    def task_space(self) -> "TwoToolSpace":
        return TwoToolSpace(self)

    @property
    def num_actions(self) -> int:
        return len(self.action_names)

    def sample_task(self, scenario: str, rng) -> TwoToolTask:
        space = self.task_space
        return space.sample(rng, space.source_distances if scenario == "source" else space.target_distances)

    def sample_tasks(self, scenario: str, n: int, rng) -> list[TwoToolTask]:
        return [self.sample_task(scenario, rng) for _ in range(n)]

    def task_sensors(self, tasks) -> np.ndarray:
        return np.array([_sensed(t.target_position, t.tools, 3) for t in tasks])

    def task_from_coordinates(self, c) -> TwoToolTask:
        if len(c) != 8:
            raise ValueError(f"a two-tool task has 8 coordinates, got {len(c)}")
        return TwoToolTask((float(c[0]), float(c[1])), (tuple(map(float, c[2:5])), tuple(map(float, c[5:8]))))

    def check_room(self, scenario: str) -> None:
        pass

    def make_env(self, scenario: str = "target", render_mode: str | None = None):
        return TwoToolEnv(self, scenario)


@dataclass(frozen=True)
class TwoToolSpace:
    """The task space's interface (env/task_space.py) over the target's distance."""

    world: TwoToolWorld

    @property
    def reach(self) -> float:
        return self.world.config.interaction_radius

    @property
    def source_distances(self) -> tuple[float, float]:
        return self.world.config.goal_radius + 0.5, self.reach - 1

    @property
    def target_distances(self) -> tuple[float, float]:
        return self.world.config.mediated_min_distance, self.world.config.mediated_max_distance

    @property
    def distances(self) -> tuple[float, float]:
        return self.source_distances[0], self.target_distances[1]

    def sample(self, rng, distance) -> TwoToolTask:
        low, high = (distance, distance) if isinstance(distance, (int, float)) else distance
        corners = [(*_polar(rng, 6.0, 8.0), float(rng.uniform(-math.pi, math.pi))) for _ in range(2)]
        return TwoToolTask(_polar(rng, low, high), tuple(corners))

    def sample_scenario(self, scenario: str, rng) -> TwoToolTask:
        return self.world.sample_task(scenario, rng)


def _sensed(target, tools, active: int) -> list[float]:
    tx, ty = target
    corners = [tool[:2] for tool in tools]
    one_hot = [0.0] * 4
    one_hot[active] = 1.0
    return [*(math.hypot(x - tx, y - ty) for x, y in corners), *(math.hypot(x, y) for x, y in corners), *one_hot]


class TwoToolEnv(gymnasium.Env):
    def __init__(self, world: TwoToolWorld, scenario: str):
        self.world, self.scenario = world, scenario
        self.action_space = gymnasium.spaces.Discrete(world.num_actions)
        self.observation_space = gymnasium.spaces.Box(0.0, 50.0, (world.sensors.size,), dtype=np.float64)
        self.task: TwoToolTask | None = None

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.task = (options or {}).get("task") or self.world.sample_task(self.scenario, self.np_random)
        self.target, self.active, self.steps = np.array(self.task.target_position), 3, 0
        return self._observation(), {"is_success": False}

    def step(self, action):
        c = self.world.config
        if action < 4:
            reachable = action != 2 or np.hypot(*self.target) <= c.interaction_radius
            self.active = int(action) if reachable else self.active
        elif self.active in (0, 1):  # pull with the held tool, if its hook reaches the target
            corner = np.array(self.task.tools[self.active][:2])
            if np.hypot(*(self.target - corner)) <= HOOKS[self.active] + 6.0:
                self.target = self.target * max(0.0, 1 - 1 / np.hypot(*self.target))
        elif self.active == 2:
            self.target = self.target * max(0.0, 1 - 1 / np.hypot(*self.target))
        self.steps += 1
        success = bool(np.hypot(*self.target) <= c.goal_radius)
        reward = float(c.success_reward) if success else 0.0
        return self._observation(), reward, success, self.steps >= c.max_episode_steps, {"is_success": success}

    def _observation(self) -> np.ndarray:
        return np.array(_sensed(self.target, self.task.tools, self.active))
