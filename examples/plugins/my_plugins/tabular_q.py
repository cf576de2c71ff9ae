"""A tabular Q-learner: one Q-value per (joint discretised state, action).

The state is the tuple of the FSR representation's active bins (one per sensor dimension:
``representation=fsr representation.distance_bins=5``), so the table grows with the states
visited. Selected like a built-in learner:

    python -m mediated_transfer algorithm=tabular_q representation=fsr \
        representation.distance_bins=5 hydra.searchpath=[pkg://my_plugins.conf]
"""

from __future__ import annotations

import numpy as np


class TabularQ:
    """Epsilon-greedy one-step Q-learning on a dict of Q-rows (the Learner interface of
    mediated_transfer/learners/base.py)."""

    representations = ("fsr",)

    def __init__(self, *, representation, num_actions: int, seed: int, world=None,
                 alpha: float = 0.2, gamma: float = 0.95, epsilon: float = 0.1):
        for key, value, low, high in (("alpha", alpha, 0.0, 1.0), ("gamma", gamma, 0.0, 1.0),
                                      ("epsilon", epsilon, 0.0, 1.0)):
            if not isinstance(value, (int, float)) or not low < value <= high:
                raise ValueError(f"algorithm.{key} must be a number in ({low:g}, {high:g}], got {value!r}")
        self.representation, self.num_actions = representation, num_actions
        self.alpha, self.gamma, self.epsilon = alpha, gamma, epsilon
        self.rng = np.random.default_rng(seed)
        self.table: dict[tuple, np.ndarray] = {}
        self._index = np.empty(representation.max_active, dtype=np.int64)
        self._value = np.empty(representation.max_active)
        self.episodes = 0

    def _row(self, observation) -> np.ndarray:
        n = self.representation.active_features(np.asarray(observation, dtype=float), self._index, self._value)
        key = tuple(self._index[:n].tolist())
        row = self.table.get(key)
        if row is None:
            row = self.table[key] = np.zeros(self.num_actions)
        return row

    def act(self, observation, explore: bool = True) -> int:
        if explore and self.rng.random() < self.epsilon:
            return int(self.rng.integers(self.num_actions))
        return int(np.argmax(self._row(observation)))

    def observe(self, observation, action, reward, next_observation, terminated) -> None:
        row = self._row(observation)
        target = reward + (0.0 if terminated else self.gamma * float(np.max(self._row(next_observation))))
        row[action] += self.alpha * (target - row[action])

    def td_error(self, observation, action, reward, next_observation, terminated) -> float:
        bootstrap = 0.0 if terminated else self.gamma * float(np.max(self._row(next_observation)))
        return reward + bootstrap - float(self._row(observation)[action])

    def end_episode(self) -> None:
        self.episodes += 1

    def divergence(self):
        return None

    def state_dict(self):
        return {"keys": np.array(list(self.table), dtype=object), "rows": np.array(list(self.table.values()))}

    def load_state_dict(self, state) -> None:
        self.table = {tuple(k): np.array(r) for k, r in zip(state["keys"], state["rows"])}

    @property
    def stats(self) -> dict[str, float]:
        return {"states": float(len(self.table)), "episodes": float(self.episodes)}
