"""The one interface every learner offers, so the experiment loop never knows which it drives.

Observations are the 11-dim sensor vectors of eq. (2): 6 distances, then the 5-dim one-hot of
the active picking location. Actions are integers in [0, num_actions).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class Learner(Protocol):
    num_actions: int

    def act(self, observation: np.ndarray, explore: bool = True) -> int:
        """Choose an action. ``explore=True``: the learner's exploring (e.g. epsilon-greedy)
        policy, drawing from the learner's own generator. ``explore=False``: the greedy policy,
        which must not change the learner in any way (not even its random stream), because
        evaluation calls it between learning steps."""

    def observe(
        self,
        observation: np.ndarray,
        action: int,
        reward: float,
        next_observation: np.ndarray,
        terminated: bool,
    ) -> None:
        """Learn from one transition. ``terminated`` means a terminal state (no bootstrap);
        a truncated episode passes ``terminated=False`` and then calls ``end_episode``."""

    def end_episode(self) -> None:
        """Close the episode (e.g. clear eligibility traces, advance a decay schedule)."""

    def divergence(self) -> str | None:
        """Why learning has diverged beyond recovery (the run is then stopped and recorded as
        failed); None while it has not. Cheap: called at every evaluation point."""

    def state_dict(self) -> dict[str, Any]:
        """Everything needed to resume: numpy arrays, torch tensors and plain numbers only."""

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what ``state_dict`` returned."""

    @property
    def stats(self) -> dict[str, float]:
        """Counters worth reporting (e.g. rolled-back updates, learning updates done)."""
