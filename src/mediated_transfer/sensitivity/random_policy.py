"""How rare discovery is in a world: the success rate of uniformly random actions on target
tasks. Before its first reward a linear learner's weights are all 0, so its greedy choice is a
fixed action and its behaviour is this random walk at best; the rate says how long the wait for
the first reward is (about 1 / (rate x episodes per step))."""

from __future__ import annotations

import numpy as np

from ..env.config import WorldConfig
from ..env.mediated_env import NUM_ACTIONS, MediatedInteractionEnv


def random_success_rate(world: WorldConfig, episodes: int, seed: int) -> float:
    """Share of ``episodes`` target-task episodes that uniformly random actions solve (the
    world's action noise applies as always). Deterministic for a seed."""
    if episodes < 1:
        raise ValueError(f"episodes must be >= 1, got {episodes!r}")
    env = MediatedInteractionEnv("target", world)
    actions = np.random.default_rng(seed)
    env.reset(seed=seed)  # the tasks' stream; each later reset continues it
    solved = 0
    for episode in range(episodes):
        if episode:
            env.reset()
        done = False
        while not done:
            _, reward, terminated, truncated, _ = env.step(int(actions.integers(NUM_ACTIONS)))
            done = terminated or truncated
        solved += bool(terminated)
    return solved / episodes
