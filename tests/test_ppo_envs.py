"""algorithm=sb3_ppo with several training environments (``algorithm.n_envs`` = K > 1, run_sb3.py):
the run's one strategy chooses and hears every episode, the learning steps and evaluation points
are the run's own, exactly, and a seed gives the same run."""

from __future__ import annotations

import numpy as np
import pytest

from .optional import importorskip

importorskip("torch")
importorskip("stable_baselines3")

from mediated_transfer.config.compose import ConfigError, compose_config
from mediated_transfer.config.spec import run_spec
from mediated_transfer.env import WorldConfig, sample_task
from mediated_transfer.recorder import RunStreams
from mediated_transfer.run import RunSpec, execute_run
from mediated_transfer.transfer.strategy import EpisodeOutcome, make_strategy

from .test_sweep import _common, _run_cli, root, source_cache  # noqa: F401

PARAMS = {"n_steps": 32, "batch_size": 32, "n_epochs": 2, "n_envs": 4}


def spec(**changes) -> RunSpec:
    values = dict(algorithm="sb3_ppo", representation="network", strategy="regular", n_source=3, seed=4,
                  algorithm_params=PARAMS, budget=600, eval_points=3, eval_episodes=2, source_pool_size=100)
    return RunSpec(**{**values, **changes})


@pytest.fixture
def heard(monkeypatch) -> list[EpisodeOutcome]:
    """Every outcome the run's strategy hears, in order."""
    outcomes: list[EpisodeOutcome] = []
    made = RunStreams.of.__func__

    def of(cls, spec_):
        streams = made(cls, spec_)
        report = streams.strategy.report
        streams.strategy.report = lambda outcome: (outcomes.append(outcome), report(outcome))[1]
        return streams

    monkeypatch.setattr(RunStreams, "of", classmethod(of))
    return outcomes


@pytest.mark.slow
def test_k_environments_run_a_smoke_sweep_through_the_table_machinery(root, source_cache):
    _run_cli("experiment=table4_dnn", "algorithm=sb3_ppo", "algorithm.n_envs=4", "algorithm.n_steps=16",
             "algorithm.batch_size=32", "cell=none_0,regular_1", "hydra/launcher=basic", *_common(root, source_cache))
    results = sorted((root / "multirun" / "table4_dnn" / "smoke").glob("*/seed=*/**/result.json"))
    assert [p.relative_to(root / "multirun" / "table4_dnn" / "smoke").parts[0] for p in results] == \
        ["none_0", "regular_1"]
    import json

    for path in results:
        result = json.loads(path.read_text())
        assert result["steps"] == [100, 200] and result["failure"] is None
        assert result["learner_stats"]["learning_steps"] == 200
        assert result["config"]["algorithm"]["n_envs"] == 4


def test_the_same_seed_gives_the_same_run(tmp_path):
    first, second = (execute_run(spec(cache_dir=str(tmp_path))) for _ in range(2))
    for key in ("steps", "mean_reward", "success_rate", "source_phase_end", "source_tasks_solved",
                "first_target_reward_step", "learner_stats", "choices"):
        assert getattr(first, key) == getattr(second, key), key
    assert first.learner_stats["updates"] > 0


def test_the_strategy_hears_every_episode_and_every_step_is_counted(tmp_path, heard):
    # 602 steps with 4 environments: neither the budget nor the evaluation points (every 301
    # steps) fall at the end of a step of the 4 environments.
    result = execute_run(spec(budget=602, eval_points=2, cache_dir=str(tmp_path)))
    assert result.steps == [301, 602]  # evaluated at the run's exact learning steps
    assert result.learner_stats["learning_steps"] == 602  # stopped at the budget exactly
    assert sum(o.length for o in heard) == 602  # every learning step is in a reported episode
    assert len(heard) == sum(result.choices["episodes"])  # each episode recorded once
    assert [o.step for o in heard] == sorted(o.step for o in heard) and heard[-1].step == 602
    assert any(o.task is not None for o in heard)  # source episodes count as learning steps
    # Episodes ended with the run are heard too: at most one per environment.
    assert 0 <= len(heard) - result.learner_stats["episodes"] <= PARAMS["n_envs"]


def test_regular_transfer_hands_over_and_the_episodes_in_flight_finish_their_source_tasks(tmp_path, heard):
    # A larger goal (as the standing runs have it): chance solves C within the short budget.
    s = spec(budget=4000, eval_points=2, world=WorldConfig(goal_radius=4.0), algorithm_params=
             {**PARAMS, "n_steps": 64, "batch_size": 64}, seed=3, cache_dir=str(tmp_path))
    result = execute_run(s)
    end = result.source_phase_end
    assert end is not None and result.source_tasks_solved == 3
    late_sources = [o for o in heard if o.task is not None and o.step > end]
    assert len(late_sources) <= PARAMS["n_envs"] - 1  # the episodes in flight at the hand-over
    assert any(o.task is None and o.step > end for o in heard)  # the target task after it
    assert all(o.task is not None for o in heard if o.step < end)  # no target task before it


def test_a_strategy_accepts_k_episodes_in_flight_and_a_task_leaves_c_once():
    world = WorldConfig()
    tasks = [sample_task("source", np.random.default_rng(i), world) for i in range(2)]
    strategy = make_strategy("regular", tasks, rng=np.random.default_rng(0))
    strategy.max_in_flight = 3
    handed = [strategy.next_task() for _ in range(3)]
    with pytest.raises(RuntimeError, match="3 episodes in flight"):
        strategy.next_task()
    twice = next(t for t in handed if sum(u is t for u in handed) > 1)  # 3 from 2 tasks: one twice
    for task in handed:  # reported out of order; the task handed out twice is solved twice
        if task is not twice:
            strategy.report(EpisodeOutcome(task, False, 0.0, 10, 10))
    strategy.report(EpisodeOutcome(twice, True, 1.0, 10, 20))
    strategy.report(EpisodeOutcome(twice, True, 1.0, 10, 30))
    assert strategy.solved_count == 1 and strategy.remaining == 1


@pytest.mark.parametrize("overrides, message", [
    (["algorithm.n_envs=0"], "algorithm.n_envs must be an integer in [1, 256], got 0"),
    (["algorithm.n_envs=4", "algorithm.n_steps=8", "algorithm.batch_size=64"],
     "algorithm.batch_size (64) must be <= algorithm.n_steps x algorithm.n_envs (8 x 4)"),
])
def test_bad_n_envs_are_refused_in_one_line(overrides, message):
    with pytest.raises(ConfigError) as caught:
        run_spec(compose_config(["algorithm=sb3_ppo", "scale=smoke", "tracking=none", *overrides]))
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_a_strategy_that_hears_one_episode_at_a_time_is_refused_with_k_environments():
    s = spec(strategy="dr", strategy_target="auto_curricula.domain_randomisation.DomainRandomisation", n_source=0)
    with pytest.raises(ValueError) as caught:
        s.validate()
    assert "algorithm.n_envs=4 keeps 4 episodes in flight" in str(caught.value) and "\n" not in str(caught.value)
