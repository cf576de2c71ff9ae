"""Issue 42's level sets and the curricula built on them (src/auto_curricula: level_sets.py,
plr_annulus.py, handover.py, sfl.py), on scripted outcomes, and every curriculum's config: each
strategy YAML builds its class with its keys, and each cell names a strategy that exists."""

from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf
from scipy import stats

import auto_curricula
from auto_curricula.handover import LearnabilityHandover, PLRHandover
from auto_curricula.level_sets import LevelSet
from auto_curricula.plr_annulus import PLRAnnulus
from auto_curricula.sfl import SamplingForLearnability
from mediated_transfer import plugins
from mediated_transfer.env import sample_tasks
from mediated_transfer.recorder import _EVAL_TASK_STREAM, _stream_seed
from mediated_transfer.transfer import StrategyContext
from mediated_transfer.transfer.strategy import Strategy

from .test_curricula import SPACE, context, outcome

CONF = Path(auto_curricula.__file__).parent / "conf"
PLR = dict(temperature=0.1, staleness=0.1)
LEARNABILITY = dict(buffer_size=2, buffer_share=0.5, window=10)
SFL = dict(buffer_share=0.5, buffer_size=10, batch_levels=40, rollouts=5)


def eval_tasks(seed, n=100):
    """A run's evaluation tasks (run.py's RunStreams.eval_tasks) for ``seed``."""
    return sample_tasks("target", n, np.random.default_rng(_stream_seed(seed, _EVAL_TASK_STREAM)))


def binomial_ok(count, n, p, sigmas=4.0):
    return abs(count - n * p) <= sigmas * np.sqrt(n * p * (1 - p))


# --- level sets -------------------------------------------------------------------------------


def test_a_level_set_of_c_refuses_an_empty_c():
    with pytest.raises(ValueError, match="n_source must be >= 1"):
        LevelSet.of_c(context(), "plr_handover")
    with pytest.raises(ValueError, match="n_source must be >= 1"):
        LevelSet.with_annulus(context(), "plr_annulus", 3, 0)
    levels = LevelSet.of_c(context(n_tasks=3), "plr_handover")
    assert levels.tasks == context(n_tasks=3).source_tasks and levels.count == levels.sources == 3


def test_annulus_levels_follow_c_and_are_the_same_for_every_run():
    c = context(n_tasks=5).source_tasks
    levels = LevelSet.with_annulus(context(seed=0, n_tasks=5), "plr_annulus", 50, 0)
    assert levels.tasks[:5] == c and levels.sources == 5 and levels.count == 55
    annulus = levels.tasks[5:]
    near, far = SPACE.target_distances
    assert all(near <= t.target_distance <= far for t in annulus)
    assert len({t.target_position for t in annulus}) == 50
    # Another run's stream (the strategy's rng) draws the same levels; another level_seed others.
    assert LevelSet.with_annulus(context(seed=99, n_tasks=5), "plr_annulus", 50, 0).tasks == levels.tasks
    other = LevelSet.with_annulus(context(seed=0, n_tasks=5), "plr_annulus", 50, 1).tasks[5:]
    assert not {t.target_position for t in other} & {t.target_position for t in annulus}
    # The first levels of a longer set are the shorter set's (one stream, drawn in order).
    assert LevelSet.with_annulus(context(n_tasks=5), "plr_annulus", 10, 0).tasks[5:] == annulus[:10]
    # Drawing the levels leaves the run's strategy stream untouched.
    ctx = context(seed=7, n_tasks=5)
    LevelSet.with_annulus(ctx, "plr_annulus", 50, 0)
    assert ctx.rng.random() == np.random.default_rng(7).random()


@pytest.mark.parametrize("level_seed", [0, 1, 3])
def test_annulus_levels_are_none_of_a_runs_evaluation_tasks(level_seed):
    annulus = LevelSet.with_annulus(context(n_tasks=1), "plr_annulus", 200, level_seed).tasks[1:]
    positions = {t.target_position for t in annulus}
    for seed in range(10):
        assert not positions & {t.target_position for t in eval_tasks(seed)}, f"run seed {seed}"


def test_a_level_set_marks_only_the_tasks_of_c_solved():
    levels = LevelSet.with_annulus(context(n_tasks=3), "plr_annulus", 2, 0)
    assert levels.solved == [False] * 3 and levels.solved_count == 0 and not levels.c_solved
    for index, solved in [(3, True), (4, True), (0, False), (1, True), (1, False), (0, True)]:
        task = levels.hand_out(index)
        assert task is levels.tasks[index]
        assert levels.take(outcome(task, solved)) == index
    assert levels.solved == [True, True, False] and levels.solved_count == 2 and not levels.c_solved
    levels.take(outcome(levels.hand_out(2), True))
    assert levels.c_solved and levels.solved_count == 3
    levels.hand_out(0)
    with pytest.raises(RuntimeError, match="twice"):
        levels.hand_out(1)
    levels.take(outcome(levels.tasks[0], False))
    with pytest.raises(RuntimeError, match="did not hand out"):
        levels.take(outcome(levels.tasks[0], False))


# --- PLR over C and the target annulus ----------------------------------------------------------


def plr_annulus(seed=0, n_tasks=5, target_levels=3, level_seed=0):
    return PLRAnnulus(context(seed=seed, n_tasks=n_tasks), **PLR, target_levels=target_levels, level_seed=level_seed)


def test_plr_annulus_levels_are_c_and_the_annulus_levels_handed_out_as_tasks():
    strategy = plr_annulus(target_levels=3)
    assert strategy.levels.count == 8 and strategy.levels.sources == 5
    assert strategy.levels.tasks == LevelSet.with_annulus(context(n_tasks=5), "x", 3, 0).tasks
    assert len(strategy.seen) == len(strategy.scores) == len(strategy.last_sampled) == 8
    handed = []
    for _ in range(300):
        task = strategy.next_task()
        assert task is not None and task is strategy.levels.tasks[strategy.levels._pending]
        handed.append(strategy.levels._pending)
        strategy.report(outcome(task, True, td_error=1.0))
    assert set(handed) == set(range(8)) and strategy.seen.all()
    assert strategy.solved_count == 5 and not strategy.done  # never done: the annulus is among its levels


def test_plr_annulus_tries_unseen_levels_with_the_share_of_levels_unseen():
    strategy = plr_annulus(seed=1, target_levels=5)  # 10 levels
    strategy.seen[:4] = True  # 4 of 10 seen: an unseen level with probability 0.6
    strategy.scores[:4] = [1.0, 2.0, 3.0, 4.0]
    unseen = 0
    for _ in range(3000):
        strategy.next_task()
        unseen += strategy.levels._pending >= 4
        strategy.levels._pending = None  # no report: keep seen and scores fixed
    assert binomial_ok(unseen, 3000, 0.6)


def test_plr_annulus_replays_the_level_of_highest_td_error_most():
    strategy = plr_annulus(seed=6, target_levels=3)
    hot = 6  # an annulus level
    counts = np.zeros(8)
    for _ in range(600):
        task = strategy.next_task()
        index = strategy.levels._pending
        counts[index] += 1
        strategy.report(outcome(task, False, td_error=5.0 if index == hot else 0.1))
    assert strategy.seen.all()
    assert counts[hot] > 0.8 * 600 and counts.argmax() == hot


@pytest.mark.parametrize("key, value", [("target_levels", 0), ("target_levels", 2.0), ("target_levels", True),
                                        ("level_seed", -1), ("level_seed", 0.5), ("level_seed", None)])
def test_plr_annulus_refuses_bad_level_parameters(key, value):
    with pytest.raises(ValueError, match=f"strategy.{key}"):
        PLRAnnulus(context(n_tasks=2), **PLR, **{"target_levels": 3, "level_seed": 0, key: value})


@pytest.mark.parametrize("make, name", [
    (lambda c: PLRAnnulus(c, **PLR, target_levels=3, level_seed=0), "plr_annulus"),
    (lambda c: PLRHandover(c, **PLR), "plr_handover"),
    (lambda c: LearnabilityHandover(c, **LEARNABILITY), "learnability_handover")],
    ids=["plr_annulus", "plr_handover", "learnability_handover"])
def test_the_level_set_curricula_refuse_an_empty_c_by_their_own_name(make, name):
    """The refusal names the strategy a user chose (as LevelSet.of_c is told), not its parent's."""
    with pytest.raises(ValueError, match=f"strategy '{name}' .*n_source must be >= 1"):
        make(context())


# --- orderings of C under the paper's hand-over rule --------------------------------------------


def handovers(seed=0, n_tasks=5):
    return [PLRHandover(context(seed=seed, n_tasks=n_tasks), **PLR),
            LearnabilityHandover(context(seed=seed, n_tasks=n_tasks), **LEARNABILITY)]


def state(strategy):
    """What an outcome could change of a hand-over curriculum."""
    levels = strategy.levels
    common = (list(levels.solved), levels._pending, strategy.rng.bit_generator.state["state"]["state"])
    if isinstance(strategy, PLRHandover):
        return common + (strategy.seen.tolist(), strategy.scores.tolist(), strategy.last_sampled.tolist(),
                         strategy.episodes)
    return common + (strategy.successes.tolist(), strategy.tries.tolist(), [list(h) for h in strategy.history])


@pytest.mark.parametrize("index", [0, 1])
def test_a_handover_curriculum_orders_c_until_every_task_was_solved_then_is_done(index):
    strategy = handovers(seed=10 + index)[index]
    c = strategy.levels.tasks
    assert strategy.source_tasks == "required" and strategy.levels.count == 5 and not strategy.done
    last = 4  # solved last: every other task of C is solved whenever it is handed out first
    handed, solved_again = [], False
    while True:
        assert not strategy.done
        task = strategy.next_task()
        level = strategy.levels._pending
        assert task is not None and task is c[level]  # only tasks of C, never a target task
        if level != last:
            solved_again |= strategy.levels.solved[level]
        handed.append(level)
        strategy.report(outcome(task, level != last or len(handed) > 200, td_error=1.0 + level))
        if strategy.done:
            break
    # Done exactly at the report that solved the last unsolved task, not before.
    assert handed[-1] == last and len(handed) > 200
    assert strategy.levels.solved == [True] * 5 and strategy.solved_count == 5
    # Solved tasks stayed among its levels: handed out again before the hand-over.
    assert solved_again
    assert len(set(handed[:200])) == 5


@pytest.mark.parametrize("index", [0, 1])
def test_a_handover_curriculum_takes_target_episodes_after_it_is_done_and_changes_nothing(index):
    strategy = handovers(seed=20 + index, n_tasks=2)[index]
    while not strategy.done:
        task = strategy.next_task()
        strategy.report(outcome(task, True, td_error=0.3))
    before = state(strategy)
    for solved in (True, False, True):
        strategy.report(outcome(None, solved, td_error=9.0))
    assert state(strategy) == before and strategy.done


def test_learnability_handover_buffers_the_tasks_of_c_nearest_p_one_half():
    strategy = LearnabilityHandover(context(seed=7, n_tasks=5), buffer_size=2, buffer_share=0.5, window=10)
    c = strategy.levels.tasks
    success = [1.0, 0.5, 0.2, 0.0, 0.6]
    for level, p in enumerate(success):
        for solved in [True] * round(10 * p) + [False] * (10 - round(10 * p)):
            strategy.levels._pending = level
            strategy.report(outcome(c[level], solved))
    np.testing.assert_allclose(strategy.learnability(), [0, 0.25, 0.16, 0, 0.24])
    assert strategy.buffer().tolist() == [1, 4]
    assert not strategy.done  # task 3 never solved
    counts = np.zeros(5)
    for _ in range(5000):
        task = strategy.next_task()
        assert task is not None
        counts[strategy.levels._pending] += 1
        strategy.levels._pending = None  # outcomes would move p: keep the buffer fixed here
    expected = np.full(5, 0.5 / 5)
    expected[[1, 4]] += 0.25
    np.testing.assert_allclose(counts / 5000, expected, atol=0.025)


# --- Sampling For Learnability ------------------------------------------------------------------


def sfl(seed=0, **params):
    return SamplingForLearnability(context(seed=seed), **{**SFL, **params})


def play(strategy, solves, episodes):
    """``episodes`` episodes, a batch level solved when ``solves(batch index, attempt)`` and a
    buffer level always; returns how many came from the buffer."""
    from_buffer = 0
    for _ in range(episodes):
        task = strategy.next_task()
        level = strategy._pending
        if level < 0:
            from_buffer += 1
            strategy.report(outcome(task, True))
        else:
            attempt = int(strategy.tried[level])
            strategy.report(outcome(task, solves(level, attempt)))
    return from_buffer


def test_sfl_draws_fresh_levels_uniformly_over_the_task_space():
    low, high = SPACE.distances
    strategy = sfl(seed=1)
    distances = []
    for _ in range(6):
        batch = list(strategy.batch)
        distances += [t.target_distance for t in batch]
        rebuilds = strategy.rebuilds
        while strategy.rebuilds == rebuilds:
            play(strategy, lambda level, attempt: attempt < 2, 1)
        assert not set(map(id, batch)) & set(map(id, strategy.batch))  # a fresh batch
    distances = np.array(distances)
    assert len(distances) == 240 and distances.min() >= low and distances.max() <= high
    assert stats.kstest(distances, stats.uniform(loc=low, scale=high - low).cdf).pvalue > 0.01
    target_from = SPACE.target_distances[0]
    assert np.any(distances >= target_from)  # the annulus is the generator's far end


def test_sfl_plays_each_batch_level_rollouts_times_before_the_rebuild():
    strategy = sfl(seed=2, batch_levels=7, rollouts=3, buffer_share=0.5)
    for batch_number in range(3):
        batch, counts = list(strategy.batch), np.zeros(7)
        while strategy.rebuilds == batch_number:
            task = strategy.next_task()
            level = strategy._pending
            if level >= 0:
                assert task is batch[level]
                counts[level] += 1
            strategy.report(outcome(task, level >= 0 and counts[level] == 1))  # p = 1/3: every level buffered
        assert counts.tolist() == [3] * 7
        assert strategy.tried.tolist() == [0] * 7 and strategy.batch[0] is not batch[0]


@pytest.mark.parametrize("buffer_size, expected", [(2, [2, 4]), (3, [2, 4, 1]), (10, [2, 4, 1, 5])])
def test_sfl_rebuilds_its_buffer_from_the_batch_levels_of_highest_learnability(buffer_size, expected):
    strategy = sfl(seed=3, batch_levels=8, rollouts=5, buffer_size=buffer_size)
    solved = [0, 1, 2, 5, 3, 4, 0, 5]  # of 5: p (1 - p) = 0, .16, .24, 0, .24, .16, 0, 0
    batch = list(strategy.batch)
    assert play(strategy, lambda level, attempt: attempt < solved[level], 40) == 0  # no buffer yet
    assert strategy.rebuilds == 1
    assert strategy.buffer == [batch[i] for i in expected]  # ties: the lower index first

    # The next rebuild replaces the buffer (nothing of the first batch stays) ...
    second = list(strategy.batch)
    while strategy.rebuilds == 1:
        play(strategy, lambda level, attempt: level == 6 or attempt < 2 * (level == 3), 1)
    assert strategy.buffer == [second[3]]
    # ... and a batch without a level of learnability > 0 empties it.
    while strategy.rebuilds == 2:
        play(strategy, lambda level, attempt: level % 2 == 0, 1)
    assert strategy.buffer == []


@pytest.mark.parametrize("share", [0.5, 0.2])
def test_sfl_draws_buffer_levels_at_rate_rho_once_the_buffer_is_filled(share):
    strategy = sfl(seed=4, buffer_share=share, batch_levels=10, rollouts=5)
    play(strategy, lambda level, attempt: attempt % 2 == 0, 50)  # p = 0.6 for every level
    assert strategy.rebuilds == 1 and len(strategy.buffer) == 10
    from_buffer = play(strategy, lambda level, attempt: attempt % 2 == 0, 4000)
    assert strategy.buffer  # every batch keeps some levels
    assert binomial_ok(from_buffer, 4000, share)


def test_sfl_plays_only_batch_levels_while_no_level_is_learnable():
    strategy = sfl(seed=5)
    for solves in (lambda level, attempt: False, lambda level, attempt: True):  # p = 0 or 1: nothing buffered
        assert play(strategy, solves, 600) == 0
        assert strategy.buffer == []
    assert strategy.rebuilds == 6 and not strategy.done


def test_sfl_is_deterministic_for_a_seed():
    def sequence(seed):
        strategy = sfl(seed=seed, batch_levels=6, rollouts=5)
        tasks = []
        for _ in range(200):
            task = strategy.next_task()
            tasks.append(task.target_position)
            strategy.report(outcome(task, len(tasks) % 3 == 0))
        return tasks, strategy.rebuilds

    assert sequence(8) == sequence(8)
    assert sequence(8)[0] != sequence(9)[0]


@pytest.mark.parametrize("key, value", [
    ("buffer_size", 0), ("buffer_size", 2.5), ("batch_levels", 0), ("batch_levels", True), ("rollouts", -1),
    ("rollouts", "5"), ("buffer_share", 1.0), ("buffer_share", -0.1), ("buffer_share", True), ("buffer_share", "0.5")])
def test_sfl_refuses_bad_parameters(key, value):
    with pytest.raises(ValueError, match=f"strategy.{key}"):
        sfl(**{key: value})


def test_sfl_refuses_an_episode_it_did_not_hand_out():
    strategy = sfl()
    with pytest.raises(RuntimeError, match="did not hand out"):
        strategy.report(outcome(None, True))
    strategy.next_task()
    with pytest.raises(RuntimeError, match="twice"):
        strategy.next_task()


# --- every curriculum's config --------------------------------------------------------------------


STRATEGIES = sorted(p.stem for p in (CONF / "strategy").glob("*.yaml"))
CELLS = sorted(p.stem for p in (CONF / "cell").glob("*.yaml"))


def load(name):
    node = OmegaConf.to_container(OmegaConf.load(CONF / "strategy" / f"{name}.yaml"))
    target = plugins.locate("strategy", node["_target_"])
    return node, target, {k: v for k, v in node.items() if k not in ("_target_", "name")}


@pytest.mark.parametrize("name", STRATEGIES)
def test_every_strategy_config_builds_its_class_with_its_keys(name):
    node, target, params = load(name)
    assert node["name"] == name
    needs = getattr(plugins.owner_class(target), "source_tasks", "optional")
    c = context(seed=0, n_tasks=5 if needs == "required" else 0)
    strategy = plugins.call(target, params, context=c)
    assert isinstance(strategy, Strategy) and not strategy.done
    task = strategy.next_task()
    strategy.report(outcome(task, False, td_error=0.5))


@pytest.mark.parametrize("cell", CELLS)
def test_every_cell_names_a_strategy_that_exists_with_a_fitting_n_source(cell):
    defaults = OmegaConf.to_container(OmegaConf.load(CONF / "cell" / f"{cell}.yaml"))["defaults"]
    overrides = {k.removeprefix("override /"): str(v) for d in defaults for k, v in d.items()}
    strategy, n_source = overrides["strategy"], int(overrides["n_source"])
    assert strategy in STRATEGIES
    assert cell == f"{strategy}_{n_source}"
    _, target, _ = load(strategy)
    needs = getattr(plugins.owner_class(target), "source_tasks", "optional")
    assert (n_source >= 1) if needs == "required" else (n_source == 0 or needs == "optional")


def test_every_strategy_has_a_cell():
    assert sorted({c.rsplit("_", 1)[0] for c in CELLS}) == STRATEGIES
