"""Linear Q(lambda): convergence to Q*, the trace and Boyan schedule step by step, rollbacks,
the evaluation contract of act(explore=False), checkpoints, and bad hyperparameters."""

from __future__ import annotations

import io
import warnings

import numpy as np
import pytest

from mediated_transfer.learners import (
    FSRRepresentation,
    Learner,
    LinearQConfig,
    LinearQLearner,
    RBFRepresentation,
)

from .chain_mdp import NUM_ACTIONS, RIGHT, ChainMDP

REPRESENTATIONS = {"rbf": RBFRepresentation, "fsr": FSRRepresentation}


def observation(distance: float, active: int = 4) -> np.ndarray:
    obs = np.zeros(11)
    obs[:6] = distance
    obs[6 + active] = 1.0
    return obs


def run_chain(learner: LinearQLearner, env: ChainMDP, episodes: int, max_steps: int = 30) -> list[int]:
    actions = []
    for _ in range(episodes):
        obs = env.reset()
        for _ in range(max_steps):
            a = learner.act(obs)
            actions.append(a)
            nxt, r, done = env.step(a)
            learner.observe(obs, a, r, nxt, done)
            obs = nxt
            if done:
                break
        learner.end_episode()
    return actions


def test_implements_the_learner_protocol():
    assert isinstance(LinearQLearner(LinearQConfig(), FSRRepresentation()), Learner)


@pytest.mark.parametrize("lambda_", [0.0, 0.5])
@pytest.mark.parametrize("name", ["rbf", "fsr"])
def test_converges_to_q_star_on_a_chain(name, lambda_):
    """Chain of 5 states at distances 1, 5, 9, 13 (+17 terminal): spacing 4 puts the states on
    different RBF centres and FSR bins, so Q* is representable. The chain is deterministic, so
    Q* is also a fixed point of Q(lambda) with uncut traces. Tolerance: 1e-3 (Q* <= 10)."""
    gamma = 0.9
    config = LinearQConfig(epsilon=0.5, lambda_=lambda_, gamma=gamma, alpha0=1.0, boyan_n0=1e4)
    learner = LinearQLearner(config, REPRESENTATIONS[name](), NUM_ACTIONS, seed=1)
    env = ChainMDP(n=5, spacing=4.0, offset=1.0)
    run_chain(learner, env, episodes=800)
    q = np.array([learner.q_values(env.observation(s)) for s in range(env.n - 1)])
    np.testing.assert_allclose(q, env.q_star(gamma), rtol=0, atol=1e-3)
    assert all(learner.act(env.observation(s), explore=False) == RIGHT for s in range(env.n - 1))
    assert learner.stats["rollbacks"] == 0


def test_traces_and_updates_on_a_scripted_sequence():
    """FSR, gamma 0.9, lambda 0.5 (trace decay 0.45), alpha_0 0.5, N0 10: every number below
    is worked out by hand. States A and B differ in all six distance bins and share the five
    bits (O active)."""
    config = LinearQConfig(epsilon=0.0, lambda_=0.5, gamma=0.9, alpha0=0.5, boyan_n0=10.0)
    learner = LinearQLearner(config, FSRRepresentation())
    A, B = observation(1.0), observation(5.0)
    a_dist = [2, 52, 102, 154, 204, 254]  # |MiT| = 1 -> bin 2 of 0.48; |MiO| = 1 -> bin 4 of 0.24
    b_dist = [10, 60, 110, 170, 220, 270]  # 5 / 0.48 -> 10; 5 / 0.24 -> 20
    bits = [300, 302, 304, 306, 309]
    alpha = 0.5 / 11  # Boyan at episode 0 is alpha_0, divided by ||phi(s)||_1 = 11

    # Step 1: A -a5-> B, reward 0: delta = 0, the trace marks (A, a5) with 1.
    learner.observe(A, 5, 0.0, B, False)
    e = learner.trace()
    assert np.count_nonzero(e) == 11
    np.testing.assert_array_equal(e[5, a_dist + bits], 1.0)
    assert np.all(learner.theta == 0.0)

    # Step 2: B -a5-> A, reward 1: e = min(0.45 e + phi(B, a5), 1); delta = 1.
    learner.observe(B, 5, 1.0, A, False)
    e = learner.trace()
    np.testing.assert_allclose(e[5, a_dist], 0.45)
    np.testing.assert_allclose(e[5, bits], 1.0)  # 0.45 + 1, clipped at 1
    np.testing.assert_allclose(e[5, b_dist], 1.0)
    assert np.count_nonzero(e) == 17
    theta = learner.theta.copy()
    np.testing.assert_allclose(theta[5, a_dist], alpha * 0.45)
    np.testing.assert_allclose(theta[5, bits + b_dist], alpha)
    assert np.count_nonzero(theta) == 17  # only traced weights were touched
    assert learner.q_values(B)[5] == pytest.approx(alpha * 11)

    # Step 3: A -a2-> terminal, reward 2: no bootstrap, so delta = 2 - Q(A, a2) = 2 although
    # Q(B, a5) = 0.5 > 0. The trace before the update: 0.45 * e plus phi(A, a2).
    learner.observe(A, 2, 2.0, B, True)
    step = (learner.theta - theta) / (alpha * 2.0)
    np.testing.assert_allclose(step[5, a_dist], 0.45 * 0.45)
    np.testing.assert_allclose(step[5, bits + b_dist], 0.45)
    np.testing.assert_allclose(step[2, a_dist + bits], 1.0)
    assert np.count_nonzero(step) == 17 + 11

    # The terminal transition closed the episode: traces zeroed, Boyan advanced once.
    assert not learner.trace().any()
    assert learner.stats["episodes"] == 1
    learner.end_episode()  # the loop's end_episode after a terminal step changes nothing
    assert learner.stats["episodes"] == 1
    assert learner.learning_rate == pytest.approx(0.5 * 11 / (10 + 2**1.1))


def test_traces_stay_sparse_within_a_long_episode():
    """gamma * lambda = 0.45: an entry falls below the 1e-4 cutoff 12 steps after it was last
    set (0.45^12 = 7e-5), so the trace never holds more than 12 steps' worth of the 11 FSR
    features, however long the episode."""
    config = LinearQConfig(epsilon=1.0, lambda_=0.5, gamma=0.9)
    learner = LinearQLearner(config, FSRRepresentation(), seed=4)
    env = ChainMDP(n=50, spacing=0.45, offset=0.5)  # a long chain: no termination in 300 steps
    obs = env.reset()
    sizes = []
    for _ in range(300):
        a = learner.act(obs)
        nxt, r, done = env.step(a)
        learner.observe(obs, a, r, nxt, done)
        obs = nxt
        sizes.append(np.count_nonzero(learner.trace()))
    assert not done
    assert 11 < max(sizes) <= 12 * 11


def test_boyan_schedule_values():
    learner = LinearQLearner(LinearQConfig(alpha0=0.5, boyan_n0=10.0), FSRRepresentation())
    A, B = observation(1.0), observation(5.0)
    # alpha_0 (N0 + 1) / (N0 + (episode + 1) ** 1.1), by hand: 2^1.1 = 2.14355, 3^1.1 = 3.34837.
    expected = [0.5, 0.4529154483394, 0.4120353419115, 0.3768467179856]
    for episode, rate in enumerate(expected):
        assert learner.learning_rate == pytest.approx(rate, rel=1e-12)
        learner.observe(A, 0, 0.0, B, False)
        learner.end_episode()
        assert learner.stats["episodes"] == episode + 1
    # An episode without learning transitions (e.g. evaluation) does not advance the schedule.
    learner.end_episode()
    assert learner.stats["episodes"] == len(expected)


def test_other_learning_rate_modes():
    const = LinearQLearner(LinearQConfig(alpha_decay="const", alpha0=0.3), FSRRepresentation())
    boyan_const = LinearQLearner(LinearQConfig(alpha_decay="boyan_const", alpha0=0.3, boyan_n0=10.0),
                                 FSRRepresentation())
    A, B = observation(1.0), observation(5.0)
    for learner in (const, boyan_const):
        learner.observe(A, 0, 1.0, B, False)
        learner.end_episode()
    assert const.learning_rate == 0.3
    assert boyan_const.learning_rate == pytest.approx(0.3 * 11 / (10 + 2**1.1))
    # Neither divides by ||phi||_1: one update of delta = 1 moves each active weight by alpha.
    np.testing.assert_allclose(const.theta[0][const.theta[0] != 0], 0.3)
    np.testing.assert_allclose(boyan_const.theta[0][boyan_const.theta[0] != 0], 0.3)


def test_a_diverging_update_is_rolled_back_counted_and_warned_once():
    config = LinearQConfig(alpha_decay="const", alpha0=1.0, lambda_=0.0, epsilon=0.0)
    learner = LinearQLearner(config, FSRRepresentation())
    A, B = observation(1.0), observation(5.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(10):
            before = learner.theta.copy()
            learner.observe(A, 0, 1.5e308, B, False)  # drives theta towards overflow
            if learner.stats["rollbacks"]:
                break
        assert learner.stats["rollbacks"] == 1
        np.testing.assert_array_equal(learner.theta, before)  # the whole update undone
        learner.observe(A, 0, np.inf, B, False)
        assert learner.stats["rollbacks"] == 2
    assert np.all(np.isfinite(learner.theta))
    assert sum(issubclass(w.category, RuntimeWarning) for w in caught) == 1


def test_greedy_act_leaves_the_learner_untouched():
    env = ChainMDP()
    twin_a = LinearQLearner(LinearQConfig(epsilon=0.3), RBFRepresentation(), seed=7)
    twin_b = LinearQLearner(LinearQConfig(epsilon=0.3), RBFRepresentation(), seed=7)
    run_chain(twin_a, env, episodes=5)
    run_chain(twin_b, env, episodes=5)
    # Mid-episode, as evaluation happens: twin_b is evaluated between two learning steps.
    obs = env.reset()
    for learner in (twin_a, twin_b):
        a = learner.act(obs)
        learner.observe(obs, a, 0.0, env.observation(1), False)
    rng_state = twin_b._rng.bit_generator.state
    snapshot = {k: np.copy(v) for k, v in twin_b.state_dict().items()}
    for s in range(env.n - 1):
        twin_b.act(env.observation(s), explore=False)
    assert twin_b._rng.bit_generator.state == rng_state
    for key, value in twin_b.state_dict().items():
        np.testing.assert_array_equal(value, snapshot[key], err_msg=key)
    # ... so both twins go on identically.
    assert run_chain(twin_a, env, episodes=5) == run_chain(twin_b, env, episodes=5)
    np.testing.assert_array_equal(twin_a.theta, twin_b.theta)


def test_ties_greedy_lowest_index_exploring_random_but_seeded():
    fresh = LinearQLearner(LinearQConfig(epsilon=0.0), FSRRepresentation(), seed=3)
    obs = observation(3.0)
    assert fresh.act(obs, explore=False) == 0  # all Q = 0: the lowest index
    picks = [fresh.act(obs) for _ in range(200)]
    assert len(set(picks)) == NUM_ACTIONS  # ties broken at random when exploring
    again = LinearQLearner(LinearQConfig(epsilon=0.0), FSRRepresentation(), seed=3)
    assert [again.act(obs) for _ in range(200)] == picks


def test_epsilon_greedy():
    greedy = LinearQLearner(LinearQConfig(epsilon=0.0), FSRRepresentation())
    obs = observation(3.0)
    greedy.theta[7, :] = 1.0  # action 7 is best everywhere
    assert all(greedy.act(obs) == 7 for _ in range(50))
    random = LinearQLearner(LinearQConfig(epsilon=1.0), FSRRepresentation())
    random.theta[7, :] = 1.0
    counts = np.bincount([random.act(obs) for _ in range(2200)], minlength=NUM_ACTIONS)
    assert counts.min() > 120  # ~200 each: uniform over the 11 actions


@pytest.mark.parametrize("name", ["rbf", "fsr"])
def test_checkpoint_round_trip_mid_episode(name):
    env_a, env_b = ChainMDP(), ChainMDP()
    learner = LinearQLearner(LinearQConfig(epsilon=0.3), REPRESENTATIONS[name](), seed=5)
    run_chain(learner, env_a, episodes=20)
    obs = env_a.reset()
    for _ in range(2):  # stop mid-episode, with a live trace
        a = learner.act(obs)
        nxt, r, done = env_a.step(a)
        learner.observe(obs, a, r, nxt, done)
        obs = nxt
    buffer = io.BytesIO()
    np.savez(buffer, **learner.state_dict())
    buffer.seek(0)
    with np.load(buffer, allow_pickle=False) as saved:  # plain arrays, no pickle
        state = dict(saved)
    restored = LinearQLearner(LinearQConfig(epsilon=0.3), REPRESENTATIONS[name](), seed=99)
    restored.load_state_dict(state)
    np.testing.assert_array_equal(restored.trace(), learner.trace())
    env_b.state = env_a.state
    for env, agent in ((env_a, learner), (env_b, restored)):
        o = env.observation(env.state)
        actions = []
        for _ in range(40):
            a = agent.act(o)
            actions.append(a)
            nxt, r, done = env.step(a)
            agent.observe(o, a, r, nxt, done)
            o = env.reset() if done else nxt
            if done:
                agent.end_episode()
        agent.actions = actions
    assert learner.actions == restored.actions
    np.testing.assert_array_equal(learner.theta, restored.theta)
    assert learner.stats == restored.stats


def test_checkpoint_of_another_representation_is_refused():
    state = LinearQLearner(LinearQConfig(), FSRRepresentation()).state_dict()
    with pytest.raises(ValueError, match="theta"):
        LinearQLearner(LinearQConfig(), RBFRepresentation()).load_state_dict(state)


@pytest.mark.parametrize(
    "kwargs, key",
    [
        ({"gamma": 1.0}, "algorithm.gamma"),
        ({"gamma": -0.1}, "algorithm.gamma"),
        ({"alpha0": -0.1}, "algorithm.alpha0"),
        ({"alpha0": 0.0}, "algorithm.alpha0"),
        ({"lambda_": 1.5}, "algorithm.lambda_"),
        ({"lambda_": -0.1}, "algorithm.lambda_"),
        ({"epsilon": 1.1}, "algorithm.epsilon"),
        ({"boyan_n0": -1.0}, "algorithm.boyan_n0"),
        ({"alpha_decay": "dabney"}, "algorithm.alpha_decay"),
        ({"trace_cutoff": 1.0}, "algorithm.trace_cutoff"),
        ({"gamma": "0.9"}, "algorithm.gamma"),
    ],
)
def test_bad_hyperparameters_raise_at_construction(kwargs, key):
    with pytest.raises(ValueError, match=key):
        LinearQConfig(**kwargs)


def test_bad_actions_and_action_counts_raise():
    learner = LinearQLearner(LinearQConfig(), FSRRepresentation())
    with pytest.raises(ValueError, match="action"):
        learner.observe(observation(1.0), 11, 0.0, observation(2.0), False)
    with pytest.raises(ValueError, match="num_actions"):
        LinearQLearner(LinearQConfig(), FSRRepresentation(), num_actions=0)
