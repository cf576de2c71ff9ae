"""The paper's world with one more sensor: the target's distance to the origin O, |TO|, after
the six distances of eq. (2) (the paper's agent does not observe it).

    python -m mediated_transfer env=target_distance representation=fsr \
        hydra.searchpath=[pkg://my_worlds.conf]
"""

from __future__ import annotations

import math

import gymnasium
import numpy as np

from mediated_transfer.env.paper import PaperWorld


class TargetDistanceWorld(PaperWorld):
    sensors = PaperWorld.sensors.with_distance("TO", "origin")

    def make_env(self, scenario: str = "target", render_mode: str | None = None):
        return TargetDistance(super().make_env(scenario, render_mode), self.config.world_radius)

    def task_sensors(self, tasks):
        # C is clustered, and eq. (3) compares tasks, on what this agent observes: |TO| too.
        return np.insert(super().task_sensors(tasks), 6, [t.target_distance for t in tasks], axis=1)


class TargetDistance(gymnasium.ObservationWrapper):
    """Inserts |TO| after the distances, before the one-hot of the active picking location."""

    def __init__(self, env: gymnasium.Env, world_radius: float):
        super().__init__(env)
        space, self._at = env.observation_space, 6
        self.observation_space = gymnasium.spaces.Box(
            np.insert(space.low, self._at, 0.0), np.insert(space.high, self._at, world_radius), dtype=np.float64)

    def observation(self, observation):
        return np.insert(observation, self._at, math.hypot(*self.env.unwrapped.target_position))
