"""The learners of a lockstep group: K runs' learners behind one interface, so the lockstep
loop never knows whether they compute one by one or stacked.

- ``PerSeedLearners`` (``lockstep.device=cpu``): each run's own learner, called exactly as
  ``run.execute_run`` calls it. On a CPU a single DQN update already runs its matrix products
  near the machine's matmul rate, so stacking buys nothing there (``make bench``: the stacked
  update is slower per network); this way every run's curve is its single run's, bit for bit.
- ``StackedDQN`` (``lockstep.device=cuda``, lockstep/stacked.py): the K networks stacked on the
  device, one batched forward and one batched update per step.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from ..learners.base import Learner

DEVICES = ("cpu", "cuda")


class LearnerGroup(Protocol):
    def act(self, members: list[int], observations: list[np.ndarray], explore: bool) -> list[int]:
        """The action of each member run (indices into the group) for its observation."""

    def observe(self, k: int, observation, action: int, reward: float, next_observation,
                terminated: bool) -> None:
        """Run k's transition of this step."""

    def learn(self) -> None:
        """After every active run has observed its transition of the step."""

    def end_episode(self, k: int) -> None:
        """Run k's episode has ended."""

    def learner(self, k: int, with_buffer: bool = False) -> Learner:
        """Run k's learner as of now, for evaluation, divergence checks, statistics, saving."""


class PerSeedLearners:
    """Each run's own learner, one after the other (any ``Learner``)."""

    def __init__(self, learners: Sequence[Learner]):
        self.learners = list(learners)

    def act(self, members: list[int], observations: list[np.ndarray], explore: bool) -> list[int]:
        return [self.learners[k].act(obs, explore=explore) for k, obs in zip(members, observations)]

    def observe(self, k: int, observation, action: int, reward: float, next_observation,
                terminated: bool) -> None:
        self.learners[k].observe(observation, action, reward, next_observation, terminated)

    def td_error(self, k: int, observation, action: int, reward: float, next_observation,
                 terminated: bool) -> float:
        """Run k's TD error of this transition, before it observes it (a strategy that asks for
        TD errors; a group without this method refuses such a strategy)."""
        return self.learners[k].td_error(observation, action, reward, next_observation, terminated)

    def learn(self) -> None:
        pass  # each learner updated itself in observe, as in a single run

    def end_episode(self, k: int) -> None:
        self.learners[k].end_episode()

    def learner(self, k: int, with_buffer: bool = False) -> Learner:
        return self.learners[k]
