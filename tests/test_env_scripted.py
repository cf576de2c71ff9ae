"""The geometry and physics allow both scenarios to be solved: scripted policies prove it."""

import numpy as np

from mediated_transfer.env import MediatedInteractionEnv, WorldConfig
from mediated_transfer.env.mediated_env import NUM_ACTIONS
from mediated_transfer.env.scripted import ScriptedDirectPolicy, ScriptedToolPolicy

NOISELESS = WorldConfig(action_noise=0.0)


def success_rate(scenario, policy_class, episodes=100, seed=0):
    env = MediatedInteractionEnv(scenario, NOISELESS)
    policy = policy_class(env)
    successes = 0
    for episode in range(episodes):
        observation, _ = env.reset(seed=seed + episode)
        terminated = truncated = False
        while not (terminated or truncated):
            observation, _, terminated, truncated, info = env.step(policy(observation))
        successes += info["is_success"]
    return successes / episodes


def test_the_tool_policy_solves_target_tasks():
    # Mediated interaction: the target is out of reach, only the hook brings it in.
    assert success_rate("target", ScriptedToolPolicy) >= 0.90


def test_the_direct_policy_solves_source_tasks():
    assert success_rate("source", ScriptedDirectPolicy) >= 0.95


def test_the_direct_policy_cannot_solve_target_tasks():
    # Without the tool the target never comes into reach: the target task needs the mediator.
    assert success_rate("target", ScriptedDirectPolicy, episodes=20) == 0.0


def test_a_random_policy_rarely_solves_target_tasks():
    env = MediatedInteractionEnv("target", NOISELESS)
    rng = np.random.default_rng(0)
    successes = 0
    for episode in range(30):
        env.reset(seed=episode)
        terminated = truncated = False
        while not (terminated or truncated):
            _, _, terminated, truncated, _ = env.step(int(rng.integers(NUM_ACTIONS)))
        successes += terminated
    assert successes <= 3
