"""TransferWrapper: Algorithms 1 and 2 as a Gymnasium wrapper, driven exactly as the run loop
drives the strategy objects; inside a synchronous vector env; refused where it cannot work."""

from __future__ import annotations

from pathlib import Path

import gymnasium
import numpy as np
import pytest

from mediated_transfer.env import ENV_ID, sample_tasks
from mediated_transfer.env.mediated_env import PICK_O, MediatedInteractionEnv
from mediated_transfer.env.scripted import ScriptedDirectPolicy
from mediated_transfer.transfer import EpisodeOutcome, TransferWrapper, make_strategy, sensor_vectors

SOURCE_TASKS = sample_tasks("source", 4, np.random.default_rng(5))
# Per episode: solve it (a source task; a target task cannot be solved without the tool),
# fail it (to the step limit), or abandon it after one step (the next reset comes mid-episode).
SCRIPT = ["fail", "solve", "abandon", "solve", "fail", "abandon", "solve", "fail", "solve",
          "fail", "abandon", "fail"]


def strategy(name: str, seed: int = 3):
    tasks = SOURCE_TASKS if name != "none" else []
    return make_strategy(name, tasks, sensor_vectors(tasks), np.random.default_rng(seed))


def _play(env, outcome: str, source: bool) -> tuple[bool, bool]:
    """Play one episode as ``outcome`` says; (terminated, episode ended)."""
    solver = ScriptedDirectPolicy(env)
    for _ in range(env.unwrapped.config.max_episode_steps):
        action = solver.act() if outcome == "solve" and source else PICK_O
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            return bool(terminated), True
        if outcome == "abandon":
            return False, False
    raise AssertionError("the environment did not end the episode at its step limit")


def episodes_through_the_wrapper(strategy_, seed=11):
    env = TransferWrapper(MediatedInteractionEnv("target"), strategy_)
    _, info = env.reset(seed=seed)
    log = []
    for outcome in SCRIPT:
        task, source = env.unwrapped.task, info["source_phase"]
        solved, _ = _play(env, outcome, source)
        log.append((task, source, solved))
        _, info = env.reset()
    return log


def episodes_as_the_run_loop_drives_the_strategy(strategy_, seed=11):
    # The run loop's protocol written out with the strategy object itself: next_task before an
    # episode (None: the env samples a target task), report(outcome) after every episode,
    # an unfinished episode reported as not solved.
    env = MediatedInteractionEnv("target")
    log, env_seed = [], seed
    for outcome in SCRIPT:
        task = None if strategy_.done else strategy_.next_task()
        env.reset(seed=env_seed, options=None if task is None else {"task": task})
        env_seed = None
        solved, _ = _play(env, outcome, task is not None)
        strategy_.report(EpisodeOutcome(task, solved, 0.0, 1, 1))
        log.append((env.task, task is not None, solved))
    return log


@pytest.mark.parametrize("name", ["regular", "scaffolded", "none"])
def test_the_wrapper_starts_the_same_tasks_in_the_same_order_as_the_run_loops_strategy(name):
    through_wrapper = episodes_through_the_wrapper(strategy(name))
    reference = episodes_as_the_run_loop_drives_the_strategy(strategy(name))
    assert through_wrapper == reference
    sources = [task for task, source, _ in reference if source]
    if name == "none":
        assert not sources
        return
    # Each solve removes a task from C; once C is empty only target tasks follow.
    assert sum(solved for _, source, solved in reference if source) == len(SOURCE_TASKS)
    phases = [source for _, source, _ in reference]
    assert phases == sorted(phases, reverse=True) and not phases[-1]
    assert all(task in SOURCE_TASKS for task in sources)


def test_info_tells_the_episodes_phase_and_the_solved_count():
    env = TransferWrapper(MediatedInteractionEnv("target"), strategy("regular"))
    solver = ScriptedDirectPolicy(env)
    _, info = env.reset(seed=0)
    assert info["source_phase"] and info["solved_count"] == 0
    for solved in range(1, len(SOURCE_TASKS) + 1):
        while True:
            _, reward, terminated, truncated, info = env.step(solver.act())
            if terminated or truncated:
                break
        assert terminated and reward > 0
        assert info["source_phase"] and info["solved_count"] == solved  # counted at the end
        _, info = env.reset()
    assert not info["source_phase"] and info["solved_count"] == len(SOURCE_TASKS)
    assert not env.source_phase and env.strategy.done


def test_a_reset_before_the_episode_ends_counts_its_source_task_as_not_solved():
    env = TransferWrapper(MediatedInteractionEnv("target"), strategy("regular"))
    solver = ScriptedDirectPolicy(env)
    env.reset(seed=0)
    for _ in range(3):
        env.step(solver.act())
    env.reset()  # mid-episode
    assert env.strategy.solved_count == 0 and env.strategy.remaining == len(SOURCE_TASKS)


def test_it_wraps_the_registered_environment_and_refuses_what_it_cannot_drive():
    wrapped = TransferWrapper(gymnasium.make(ENV_ID), strategy("scaffolded"))
    assert wrapped.reset(seed=0, options={})[1]["source_phase"]
    with pytest.raises(ValueError, match="takes no options"):
        wrapped.reset(options={"task": SOURCE_TASKS[0]})
    with pytest.raises(ValueError, match="scenario 'target'"):
        TransferWrapper(MediatedInteractionEnv("source"), strategy("regular"))
    with pytest.raises(ValueError, match="wraps an environment of the world PaperWorld"):
        TransferWrapper(gymnasium.make("CartPole-v1"), strategy("regular"))
    with pytest.raises(ValueError, match="transfer strategy"):
        TransferWrapper(MediatedInteractionEnv("target"), "regular")


def test_it_wraps_any_world_s_environment(monkeypatch):
    """A plugin world (the extra-sensor example, 12 sensors): the wrapper checks the environment
    against the world it is given, and starts the strategy's tasks through the world's reset."""
    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parents[1] / "examples" / "worlds"))
    from my_worlds.sensor import TargetDistanceWorld

    world = TargetDistanceWorld()
    with pytest.raises(ValueError, match="observations of 11 sensors.*observation shape \\(12,\\)"):
        TransferWrapper(world.make_env("target"), strategy("regular"))  # the paper's world by default
    env = TransferWrapper(world.make_env("target"), strategy("regular"), world=world)
    observation, info = env.reset(seed=0)
    assert observation.shape == (world.sensors.size,) and info["source_phase"]
    assert env.unwrapped.task in SOURCE_TASKS


def _tasks_in_sync_vector_env(strategies, steps=400):
    envs = gymnasium.vector.SyncVectorEnv(
        [lambda s=s: TransferWrapper(MediatedInteractionEnv("target"), s) for s in strategies])
    solvers = [ScriptedDirectPolicy(env) for env in envs.envs]
    envs.reset(seed=0)
    started = [[env.unwrapped.task] for env in envs.envs]
    for _ in range(steps):
        _, _, terminated, truncated, info = envs.step([solver.act() for solver in solvers])
        assert set(info) >= {"source_phase", "solved_count"}
        for i, env in enumerate(envs.envs):
            if env.unwrapped.task is not started[i][-1]:
                started[i].append(env.unwrapped.task)
    envs.close()
    return started


def test_it_works_inside_a_synchronous_vector_env():
    one = strategy("regular")
    [started] = _tasks_in_sync_vector_env([one])
    # The direct policy solves every source task: C empties, then target tasks follow.
    assert one.done and one.solved_count == len(SOURCE_TASKS)
    assert started[: len(SOURCE_TASKS)] == [t for t in started if t in SOURCE_TASKS]
    assert sorted(map(SOURCE_TASKS.index, started[: len(SOURCE_TASKS)])) == list(range(len(SOURCE_TASKS)))
    assert len(started) > len(SOURCE_TASKS)
    # Sub-environments with a strategy each run a curriculum each.
    two = [strategy("regular", seed=1), strategy("scaffolded", seed=2)]
    _tasks_in_sync_vector_env(two, steps=200)
    assert all(s.solved_count > 0 for s in two)


def test_one_strategy_shared_by_concurrent_episodes_is_refused_in_one_line():
    shared = strategy("regular")
    with pytest.raises(RuntimeError, match="one task at a time") as caught:
        _tasks_in_sync_vector_env([shared, shared], steps=1)
    assert "\n" not in str(caught.value)


@pytest.mark.filterwarnings("ignore::UserWarning")  # gymnasium logs the worker's error too
@pytest.mark.parametrize("context", ["fork", "spawn"])  # a copy of C inherited, or unpickled
def test_a_subprocess_vector_env_is_refused_in_one_line(context):
    shared = strategy("regular")
    envs = gymnasium.vector.AsyncVectorEnv(
        [lambda: TransferWrapper(MediatedInteractionEnv("target"), shared)], context=context)
    try:
        with pytest.raises(RuntimeError, match="own copy of C") as caught:
            envs.reset(seed=0)
        assert "\n" not in str(caught.value)
    finally:
        envs.close(terminate=True)
