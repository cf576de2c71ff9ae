"""The world's task space: the parameters a task is sampled from, with their ranges, so that a
curriculum can choose tasks between the source and the target scenario without touching the
environment.

A task is (target position, tool corner position, tool angle). The parameter a curriculum
moves is the target's distance from the origin O: from just outside the goal area, through the
interaction range's edge (``reach``, the radius 10 of the paper), to the target tasks' annulus.
The tool always starts inside the range, as in both of the paper's scenarios.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .config import WorldConfig
from .task import Task, sample_task


@dataclass(frozen=True)
class TaskSpace:
    world: WorldConfig = WorldConfig()

    @property
    def reach(self) -> float:
        """The interaction range's radius: a target beyond it needs the mediator."""
        return self.world.interaction_radius

    @property
    def source_distances(self) -> tuple[float, float]:
        """Target distances of source tasks (the target disc inside the range, out of the goal)."""
        return self.world.goal_radius, self.world.interaction_radius - self.world.target_radius

    @property
    def target_distances(self) -> tuple[float, float]:
        """Target distances of target tasks (the annulus out of reach)."""
        return self.world.mediated_min_distance, self.world.mediated_max_distance

    @property
    def distances(self) -> tuple[float, float]:
        """Every target distance a task may have: from the source tasks' nearest to the target
        tasks' farthest."""
        return self.source_distances[0], self.target_distances[1]

    def sample(self, rng: np.random.Generator, distance: float | tuple[float, float]) -> Task:
        """A task whose target lies at ``distance`` from O (a number, or a (low, high) range
        sampled area-uniformly), at a uniform angle, with the tool inside the range."""
        low, high = (distance, distance) if isinstance(distance, (int, float)) else distance
        lowest, highest = self.distances
        if not lowest <= low <= high <= highest:
            raise ValueError(f"target distance {distance!r} outside the task space [{lowest:g}, {highest:g}]")
        tool = sample_task("source", rng, self.world)  # a tool pose inside the range
        for _ in range(10_000):
            r = math.sqrt(rng.uniform(low * low, high * high))
            phi = rng.uniform(0.0, 2.0 * math.pi)
            task = Task((r * math.cos(phi), r * math.sin(phi)), tool.tool_position, tool.tool_angle)
            if not task.problems(self.world):
                return task
            tool = sample_task("source", rng, self.world)
        raise ValueError(f"no valid task with target distance {distance!r} in 10000 draws")

    def sample_scenario(self, scenario: str, rng: np.random.Generator) -> Task:
        """A task of the paper's scenarios ("source" or "target"), as the environment samples it."""
        return sample_task(scenario, rng, self.world)
