"""A small deterministic chain MDP in the learners' observation format, with its known Q*.

States 0..n-1, start 0, state n-1 terminal. Action 0 moves right, action 1 moves left, every
other action stays. Entering the last state gives reward 10 and ends the episode. A state is
observed as 6 equal distances (state * spacing + offset) and the constant one-hot of O, so
every learner sees it through its ordinary 11-dim input.
"""

from __future__ import annotations

import numpy as np

NUM_ACTIONS = 11
RIGHT, LEFT = 0, 1


class ChainMDP:
    def __init__(self, n: int = 5, spacing: float = 4.0, offset: float = 1.0, reward: float = 10.0):
        self.n, self.spacing, self.offset, self.reward = n, spacing, offset, reward
        self.state = 0

    def observation(self, state: int) -> np.ndarray:
        obs = np.zeros(11)
        obs[:6] = self.offset + self.spacing * state
        obs[10] = 1.0
        return obs

    def reset(self) -> np.ndarray:
        self.state = 0
        return self.observation(0)

    def step(self, action: int) -> tuple[np.ndarray, float, bool]:
        if action == RIGHT:
            self.state += 1
        elif action == LEFT:
            self.state = max(self.state - 1, 0)
        done = self.state == self.n - 1
        return self.observation(self.state), (self.reward if done else 0.0), done

    def q_star(self, gamma: float) -> np.ndarray:
        """Q*(s, a) for the non-terminal states, shape (n-1, NUM_ACTIONS)."""
        v = np.array([self.reward * gamma ** (self.n - 2 - s) for s in range(self.n - 1)] + [0.0])
        q = np.zeros((self.n - 1, NUM_ACTIONS))
        for s in range(self.n - 1):
            right = s + 1
            q[s, RIGHT] = self.reward if right == self.n - 1 else gamma * v[right]
            q[s, LEFT] = gamma * v[max(s - 1, 0)]
            q[s, 2:] = gamma * v[s]
        return q
