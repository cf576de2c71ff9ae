"""Algorithms 1 and 2 on scripted solve/fail sequences, and the strategy factory."""

import numpy as np
import pytest

from mediated_transfer.config.targets import group_options
from mediated_transfer.env import Task
from mediated_transfer.env.paper import PaperWorld
from mediated_transfer.transfer import EpisodeOutcome, Strategy, StrategyContext, make_strategy
from mediated_transfer.transfer.strategies import NoTransfer, RegularTransfer, ScaffoldedTransfer


def tasks(n):
    # Only identity matters here: the strategies never look inside a task.
    return [Task((float(i), 0.0), (0.0, 0.0), 0.0) for i in range(n)]


def index_of(task):
    return int(task.target_position[0])


def rng(seed=0):
    return np.random.default_rng(seed)


def context(task_set, generator, sensors=None):
    return StrategyContext.of_tasks(task_set, generator, sensors=sensors)


def outcome(solved, task=Task((1.0, 0.0), (0.0, 0.0), 0.0)):
    """The outcome of a source episode (its task is not looked at, only that it is one)."""
    return EpisodeOutcome(task, bool(solved), 10.0 if solved else 0.0, 1, 1)


# --- Algorithm 1 ---------------------------------------------------------------------------


def test_regular_removes_a_task_when_solved_and_switches_to_the_target_task_when_c_is_empty():
    strategy = RegularTransfer(context(tasks(3), rng()))
    unsolved = {0, 1, 2}
    script = [False, False, True, False, True, False, False, True]
    for solved in script:
        assert not strategy.done
        task = strategy.next_task()
        assert index_of(task) in unsolved, "a solved task must never be chosen again"
        strategy.report(outcome(solved))
        if solved:
            unsolved.remove(index_of(task))
        assert strategy.solved_count == 3 - len(unsolved)
        assert strategy.remaining == len(unsolved)
    # The third solve empties C: every further episode is a target-task episode.
    assert strategy.done
    assert strategy.next_task() is None
    assert strategy.next_task() is None


def test_regular_samples_uniformly_from_c_and_keeps_failed_tasks():
    strategy = RegularTransfer(context(tasks(4), rng()))
    counts = np.zeros(4)
    for _ in range(4000):
        counts[index_of(strategy.next_task())] += 1
        strategy.report(outcome(False))
    assert strategy.remaining == 4
    assert np.all(np.abs(counts / 4000 - 0.25) < 0.03)


def test_regular_is_deterministic_for_a_seed():
    def sequence(seed):
        strategy, out = RegularTransfer(context(tasks(10), rng(seed))), []
        while (task := strategy.next_task()) is not None:
            out.append(index_of(task))
            strategy.report(outcome(len(out) % 3 == 0))
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
    strategy = ScaffoldedTransfer(context(tasks(5), rng(), SENSORS))
    assert strategy.most_similar_unsolved(0) == 1
    assert strategy.most_similar_unsolved(3) == 4
    assert strategy.most_similar_unsolved(4) == 3


def test_scaffolded_never_returns_a_solved_task():
    # Tasks 0, 1, 2 of SENSORS: cos(0,1) = 0.994, cos(1,2) = 0.781, cos(0,2) = 0.707.
    neighbour = {0: 1, 1: 0, 2: 1}
    firsts = set()
    for seed in range(30):  # enough seeds to start from each of the three tasks
        strategy = ScaffoldedTransfer(context(tasks(3), rng(seed), SENSORS[:3]))
        first = index_of(strategy.next_task())
        firsts.add(first)
        strategy.report(outcome(True))
        second = index_of(strategy.next_task())
        assert second == neighbour[first]
        strategy.report(outcome(True))
        assert index_of(strategy.next_task()) == ({0, 1, 2} - {first, second}).pop()
        strategy.report(outcome(True))
        assert strategy.next_task() is None
    assert firsts == {0, 1, 2}


def brute_force_most_similar(k, unsolved):
    def cos(u, v):
        return u @ v / (np.linalg.norm(u) * np.linalg.norm(v))

    return max(sorted(unsolved), key=lambda c: cos(SENSORS[k], SENSORS[c]))


def test_scaffolded_samples_at_random_until_the_first_solve():
    strategy = ScaffoldedTransfer(context(tasks(5), rng(), SENSORS))
    seen = set()
    for _ in range(200):
        seen.add(index_of(strategy.next_task()))
        strategy.report(outcome(False))
    assert seen == {0, 1, 2, 3, 4}


def test_scaffolded_then_picks_the_unsolved_task_most_similar_to_a_solved_one():
    strategy = ScaffoldedTransfer(context(tasks(5), rng(3), SENSORS))
    first = index_of(strategy.next_task())
    strategy.report(outcome(True))
    # With one solved task k the choice is no longer random: always the same neighbour of k.
    expected = brute_force_most_similar(first, set(range(5)) - {first})
    for _ in range(20):
        assert index_of(strategy.next_task()) == expected
        strategy.report(outcome(False))
    # Scripted rest: solve every second episode; each choice is the neighbour of SOME solved task.
    solved, unsolved = [first], set(range(5)) - {first}
    for episode in range(40):
        task = strategy.next_task()
        if task is None:
            break
        candidates = {brute_force_most_similar(k, unsolved) for k in solved}
        assert index_of(task) in candidates
        strategy.report(outcome(episode % 2 == 0))
        if episode % 2 == 0:
            solved.append(index_of(task))
            unsolved.remove(index_of(task))
    assert not unsolved and strategy.solved_count == 5
    assert strategy.done and strategy.next_task() is None


# --- protocol and factory -----------------------------------------------------------------


def test_report_must_follow_next_task_exactly_once():
    strategy = make_strategy("regular", tasks(2), rng=rng())
    with pytest.raises(RuntimeError, match="did not hand out"):
        strategy.report(outcome(True))
    strategy.report(outcome(True, task=None))  # a target-task episode changes nothing
    strategy.next_task()
    with pytest.raises(RuntimeError, match="twice"):
        strategy.next_task()


def test_no_transfer_never_has_a_source_phase():
    strategy = make_strategy("none", [])
    assert isinstance(strategy, NoTransfer)
    assert strategy.done and strategy.solved_count == 0
    assert strategy.next_task() is None
    strategy.report(outcome(False, task=None))
    with pytest.raises(RuntimeError):
        strategy.report(outcome(True))


def test_every_option_of_the_strategy_group_builds_behind_one_interface():
    # The options come from the config group (conf/strategy/): a new option is tested too.
    for name in group_options("strategy"):
        strategy = make_strategy(name, tasks(5) if name != "none" else [], rng=rng())
        assert isinstance(strategy, Strategy), name
        assert not strategy.done or name == "none"


def test_factory_rejects_unknown_names_and_mismatched_task_sets():
    with pytest.raises(ValueError, match="strategy=curriculum is unknown; allowed: none, regular, scaffolded"):
        make_strategy("curriculum", [])
    with pytest.raises(ValueError, match="'none' has no source phase but got 3 source tasks"):
        make_strategy("none", tasks(3))
    for name in ("regular", "scaffolded"):
        with pytest.raises(ValueError, match="n_source must be >= 1"):
            make_strategy(name, [], SENSORS[:0], rng())
    with pytest.raises(ValueError, match="one row per source task"):
        make_strategy("scaffolded", tasks(4), SENSORS, rng())
    with pytest.raises(TypeError, match="unexpected keyword argument 'k'"):
        make_strategy("regular", tasks(3), k=3)


# --- the generalised protocol in the run loop -----------------------------------------------


class OutwardCurriculum:
    """A curriculum over the task space (the shape of a reverse curriculum): a task at a target
    distance that moves outward by one unit per solved episode, hearing every episode with the
    learner's TD errors, done once the distance reaches the target tasks' annulus."""

    source_tasks = "optional"
    signals = ("td_error",)
    heard: list = []

    def __init__(self, context, start: float = 3.0):
        self.space, self.rng, self.distance = context.task_space, context.rng, start
        OutwardCurriculum.heard = []

    def next_task(self):
        return self.space.sample(self.rng, self.distance)

    def report(self, outcome):
        OutwardCurriculum.heard.append(outcome)
        if outcome.task is not None and outcome.solved:
            self.distance += 1.0

    @property
    def done(self):
        return self.distance >= self.space.target_distances[0]


def test_a_curriculum_chooses_tasks_of_the_task_space_and_hears_every_episode_with_td_errors():
    from mediated_transfer.run import RunSpec, execute_run

    spec = RunSpec(strategy="outward", strategy_target=f"{__name__}.OutwardCurriculum", strategy_params={"start": 3.0},
                   budget=3000, eval_points=2, eval_episodes=2)
    result = execute_run(spec.validate())
    heard = OutwardCurriculum.heard
    assert sum(o.length for o in heard) == 3000 and heard[-1].step == 3000
    assert all(o.td_error is not None and o.td_error >= 0 for o in heard)
    sources = [o for o in heard if o.task is not None]
    assert sources and all(abs(o.task.target_distance - 3.0) < 1e-9 for o in sources[:1])
    assert result.strategy == "outward" and sum(result.choices["episodes"]) == len(heard)


def test_the_task_space_spans_source_to_target_distances():
    from mediated_transfer.env.task_space import TaskSpace

    space = TaskSpace()
    assert space.source_distances == (2.0, 9.0) and space.target_distances == (10.5, 12.5) and space.reach == 10.0
    generator = rng(4)
    for distance in (2.5, 9.9, 11.0, (10.5, 12.5)):
        task = space.sample(generator, distance)
        assert not task.problems()
        low, high = (distance, distance) if isinstance(distance, float) else distance
        assert low - 1e-9 <= task.target_distance <= high + 1e-9
    with pytest.raises(ValueError, match="outside the task space"):
        space.sample(generator, 14.0)


class _NearSpace:
    """A task space whose tasks all lie 5 to 6 from O (the paper's sampling within it)."""

    def __init__(self, config):
        from mediated_transfer.env.task_space import TaskSpace

        self.paper = TaskSpace(config)
        self.distances, self.target_distances, self.reach = (5.0, 6.0), (10.5, 12.5), 10.0

    def sample(self, generator, distance):
        return self.paper.sample(generator, distance)


class NearWorld(PaperWorld):
    """The paper's world with a task space of its own (a plugin world's, env/door.py)."""

    @property
    def task_space(self):
        return _NearSpace(self.config)


def test_a_curriculum_moves_over_the_run_world_s_task_space():
    from auto_curricula.domain_randomisation import DomainRandomisation
    from mediated_transfer.recorder import RunStreams
    from mediated_transfer.run import RunSpec

    spec = RunSpec(strategy="dr", strategy_target="auto_curricula.domain_randomisation.DomainRandomisation",
                   world_target=f"{__name__}.NearWorld", budget=100, eval_points=1, eval_episodes=1).validate()
    # The run's loop, and a strategy built from Python with the world.
    for strategy in (RunStreams.of(spec).strategy,
                     DomainRandomisation(StrategyContext.of_tasks([], rng(0), spec.make_world()))):
        assert isinstance(strategy.space, _NearSpace)
        assert all(5.0 - 1e-9 <= strategy.next_task().target_distance <= 6.0 + 1e-9 for _ in range(5))
