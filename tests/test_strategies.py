"""Algorithms 1 and 2 on scripted solve/fail sequences, and the strategy factory."""

import numpy as np
import pytest

from mediated_transfer.env import Task
from mediated_transfer.transfer.strategies import (
    STRATEGIES,
    NoTransfer,
    RegularTransfer,
    ScaffoldedTransfer,
    TransferStrategy,
    make_strategy,
)


def tasks(n):
    # Only identity matters here: the strategies never look inside a task.
    return [Task((float(i), 0.0), (0.0, 0.0), 0.0) for i in range(n)]


def index_of(task):
    return int(task.target_position[0])


def rng(seed=0):
    return np.random.default_rng(seed)


# --- Algorithm 1 ---------------------------------------------------------------------------


def test_regular_removes_a_task_when_solved_and_switches_to_the_target_task_when_c_is_empty():
    strategy = RegularTransfer(tasks(3), rng())
    unsolved = {0, 1, 2}
    script = [False, False, True, False, True, False, False, True]
    for solved in script:
        assert strategy.in_source_phase
        task = strategy.next_task()
        assert index_of(task) in unsolved, "a solved task must never be chosen again"
        strategy.report(solved)
        if solved:
            unsolved.remove(index_of(task))
        assert strategy.solved_count == 3 - len(unsolved)
        assert strategy.remaining == len(unsolved)
    # The third solve empties C: every further episode is a target-task episode.
    assert not strategy.in_source_phase
    assert strategy.next_task() is None
    assert strategy.next_task() is None


def test_regular_samples_uniformly_from_c_and_keeps_failed_tasks():
    strategy = RegularTransfer(tasks(4), rng())
    counts = np.zeros(4)
    for _ in range(4000):
        counts[index_of(strategy.next_task())] += 1
        strategy.report(False)
    assert strategy.remaining == 4
    assert np.all(np.abs(counts / 4000 - 0.25) < 0.03)


def test_regular_is_deterministic_for_a_seed():
    def sequence(seed):
        strategy, out = RegularTransfer(tasks(10), rng(seed)), []
        while (task := strategy.next_task()) is not None:
            out.append(index_of(task))
            strategy.report(len(out) % 3 == 0)
        return out

    assert sequence(5) == sequence(5)
    assert sequence(5) != sequence(6)


# --- Algorithm 2 ---------------------------------------------------------------------------

# Cosine and Euclidean nearness disagree on purpose: task 1 points the way task 0 does but is
# 100 times longer; task 2 is near task 0 in Euclidean distance but at 45 degrees.
SENSORS = np.array(
    [
        [1.0, 0.0, 0.0],
        [90.0, 10.0, 0.0],  # cos to 0: 0.994
        [0.5, 0.5, 0.0],  # cos to 0: 0.707
        [0.0, 0.0, 1.0],  # cos to 0: 0
        [0.0, 0.1, 1.0],  # cos to 3: 0.995
    ]
)


def test_most_similar_unsolved_uses_cosine_similarity_not_euclidean_distance():
    strategy = ScaffoldedTransfer(tasks(5), SENSORS, rng())
    assert strategy.most_similar_unsolved(0) == 1
    assert strategy.most_similar_unsolved(3) == 4
    assert strategy.most_similar_unsolved(4) == 3


def test_scaffolded_never_returns_a_solved_task():
    # Tasks 0, 1, 2 of SENSORS: cos(0,1) = 0.994, cos(1,2) = 0.781, cos(0,2) = 0.707.
    neighbour = {0: 1, 1: 0, 2: 1}
    firsts = set()
    for seed in range(30):  # enough seeds to start from each of the three tasks
        strategy = ScaffoldedTransfer(tasks(3), SENSORS[:3], rng(seed))
        first = index_of(strategy.next_task())
        firsts.add(first)
        strategy.report(True)
        second = index_of(strategy.next_task())
        assert second == neighbour[first]
        strategy.report(True)
        assert index_of(strategy.next_task()) == ({0, 1, 2} - {first, second}).pop()
        strategy.report(True)
        assert strategy.next_task() is None
    assert firsts == {0, 1, 2}


def brute_force_most_similar(k, unsolved):
    def cos(u, v):
        return u @ v / (np.linalg.norm(u) * np.linalg.norm(v))

    return max(sorted(unsolved), key=lambda c: cos(SENSORS[k], SENSORS[c]))


def test_scaffolded_samples_at_random_until_the_first_solve():
    strategy = ScaffoldedTransfer(tasks(5), SENSORS, rng())
    seen = set()
    for _ in range(200):
        seen.add(index_of(strategy.next_task()))
        strategy.report(False)
    assert seen == {0, 1, 2, 3, 4}


def test_scaffolded_then_picks_the_unsolved_task_most_similar_to_a_solved_one():
    strategy = ScaffoldedTransfer(tasks(5), SENSORS, rng(3))
    first = index_of(strategy.next_task())
    strategy.report(True)
    # With one solved task k the choice is no longer random: always the same neighbour of k.
    expected = brute_force_most_similar(first, set(range(5)) - {first})
    for _ in range(20):
        assert index_of(strategy.next_task()) == expected
        strategy.report(False)
    # Scripted rest: solve every second episode; each choice is the neighbour of SOME solved task.
    solved, unsolved = [first], set(range(5)) - {first}
    for episode in range(40):
        task = strategy.next_task()
        if task is None:
            break
        candidates = {brute_force_most_similar(k, unsolved) for k in solved}
        assert index_of(task) in candidates
        strategy.report(episode % 2 == 0)
        if episode % 2 == 0:
            solved.append(index_of(task))
            unsolved.remove(index_of(task))
    assert not unsolved and strategy.solved_count == 5
    assert not strategy.in_source_phase and strategy.next_task() is None


# --- protocol and factory -----------------------------------------------------------------


def test_report_must_follow_next_task_exactly_once():
    strategy = make_strategy("regular", tasks(2), rng=rng())
    with pytest.raises(RuntimeError, match="without a pending source task"):
        strategy.report(True)
    strategy.next_task()
    with pytest.raises(RuntimeError, match="twice"):
        strategy.next_task()


def test_no_transfer_never_has_a_source_phase():
    strategy = make_strategy("none", [])
    assert isinstance(strategy, NoTransfer)
    assert not strategy.in_source_phase and strategy.solved_count == 0
    assert strategy.next_task() is None
    with pytest.raises(RuntimeError):
        strategy.report(True)


def test_factory_builds_every_strategy_behind_one_interface():
    built = {
        "none": make_strategy("none", []),
        "regular": make_strategy("regular", tasks(3), rng=rng()),
        "scaffolded": make_strategy("scaffolded", tasks(5), SENSORS, rng()),
    }
    assert set(built) == set(STRATEGIES)
    for name, strategy in built.items():
        assert strategy.name == name
        assert isinstance(strategy, TransferStrategy)


def test_factory_rejects_unknown_names_and_mismatched_task_sets():
    with pytest.raises(ValueError, match="unknown strategy 'curriculum'; allowed: none, regular, scaffolded"):
        make_strategy("curriculum", [])
    with pytest.raises(ValueError, match="'none' has no source phase but got 3 source tasks"):
        make_strategy("none", tasks(3))
    for name in ("regular", "scaffolded"):
        with pytest.raises(ValueError, match="n_source must be >= 1"):
            make_strategy(name, [], SENSORS[:0], rng())
    with pytest.raises(ValueError, match="pass sensors"):
        make_strategy("scaffolded", tasks(5), None, rng())
    with pytest.raises(ValueError, match="one row per source task"):
        make_strategy("scaffolded", tasks(4), SENSORS, rng())
    with pytest.raises(ValueError, match="pass rng"):
        make_strategy("regular", tasks(3))
