"""One learning run end to end: source phase, target phase, evaluation, the result files."""

from __future__ import annotations

import csv
import json
from dataclasses import replace

import numpy as np
import pytest

from mediated_transfer.env.paper import PaperWorld

from mediated_transfer import recorder as recorder_module
from mediated_transfer.config.spec import spec_from_dict
from mediated_transfer.env import WorldConfig, sample_tasks
from mediated_transfer.env.mediated_env import MediatedInteractionEnv
from mediated_transfer.learners.factory import make_learner
from mediated_transfer.results import CURVE_FILE, RESULT_FILE, RunResult
from mediated_transfer.recorder import evaluate
from mediated_transfer.run import RunSpec, execute_run

TINY = dict(budget=600, eval_points=3, eval_episodes=3, source_pool_size=200)


@pytest.mark.parametrize("algorithm, representation", [("linear_q", "rbf"), ("linear_q", "fsr"), ("dqn", "network")])
def test_a_tiny_run_of_each_learner_writes_a_complete_result(tmp_path, algorithm, representation):
    params = {"learning_starts": 100, "buffer_size": 1000} if algorithm == "dqn" else {}
    spec = RunSpec(algorithm=algorithm, representation=representation, strategy="regular", n_source=3,
                   seed=1, cache_dir=str(tmp_path / "cache"), algorithm_params=params, **TINY)
    result = execute_run(spec)
    result.write(tmp_path / "run")

    back = RunResult.read(tmp_path / "run")
    assert back == result
    assert back.steps == [200, 400, 600]
    assert back.code == {}  # the job writes the code version (sweep/job.py), knowing how the run ran
    assert len(back.mean_reward) == len(back.success_rate) == 3
    assert all(0.0 <= r <= 10.0 for r in back.mean_reward)
    assert back.reward_loss == pytest.approx(sum(10.0 - r for r in back.mean_reward))
    assert back.learning_steps_per_s > 0 and back.wall_time_s > 0
    assert 0 <= back.source_tasks_solved <= 3
    # The source phase ends exactly when all of C has been solved.
    assert (back.source_phase_end is not None) == (back.source_tasks_solved == 3)
    with open(tmp_path / "run" / CURVE_FILE) as fh:
        rows = list(csv.DictReader(fh))
    assert [int(r["step"]) for r in rows] == back.steps
    assert json.loads((tmp_path / "run" / RESULT_FILE).read_text())["algorithm"] == algorithm


def test_source_episodes_are_learning_steps_of_the_budget(tmp_path):
    spec = RunSpec(algorithm="linear_q", representation="fsr", strategy="scaffolded", n_source=5,
                   seed=0, cache_dir=str(tmp_path), **{**TINY, "budget": 3000})
    result = execute_run(spec)
    # Every learning step is one learner update, source and target episodes alike.
    assert result.learner_stats["updates"] == 3000
    # Source tasks (target within reach) are easy: the phase ends within this budget.
    assert result.source_tasks_solved == 5 and 0 < result.source_phase_end < 3000


@pytest.mark.parametrize("algorithm, representation, params, n_source, budget", [
    ("linear_q", "fsr", {}, 5, 3000),
    ("dqn", "network", {"learning_starts": 200, "buffer_size": 2000, "epsilon_decay_steps": 1000}, 2, 6000),
])
def test_same_spec_same_run(algorithm, representation, params, n_source, budget):
    # Long enough that the source phase ends and episodes end early on success, so exploration,
    # the strategy's choices and the physics all shape what is compared.
    spec = RunSpec(algorithm=algorithm, representation=representation, strategy="scaffolded",
                   n_source=n_source, seed=7, algorithm_params=params, **{**TINY, "budget": budget})
    first, second = execute_run(spec), execute_run(spec)
    assert first.source_phase_end is not None
    assert first.mean_reward == second.mean_reward
    assert first.source_phase_end == second.source_phase_end
    assert first.learner_stats == second.learner_stats
    other = execute_run(replace(spec, seed=8))
    assert (other.source_phase_end, other.learner_stats) != (first.source_phase_end, first.learner_stats)


def test_evaluation_settings_do_not_change_what_is_learned():
    spec = RunSpec(algorithm="linear_q", representation="fsr", strategy="regular", n_source=5, seed=2,
                   **{**TINY, "budget": 3000})
    sparse = execute_run(spec)
    dense = execute_run(replace(spec, eval_points=6, eval_episodes=5))
    assert sparse.source_phase_end == dense.source_phase_end is not None
    assert sparse.learner_stats == dense.learner_stats


def test_every_strategy_of_a_seed_is_evaluated_on_the_same_target_tasks(monkeypatch):
    seen = {}

    def recording_evaluate(learner, env, tasks, seed):
        seen.setdefault(current, []).append(([t.coordinates.tolist() for t in tasks], seed))
        return 0.0, 0.0

    monkeypatch.setattr(recorder_module, "evaluate", recording_evaluate)
    for current, (strategy, n) in {"none": ("none", 0), "scaffolded": ("scaffolded", 3)}.items():
        execute_run(RunSpec(strategy=strategy, n_source=n, seed=5, representation="fsr", **TINY))
    assert seen["none"] == seen["scaffolded"]
    assert len(seen["none"]) == 3 and len(seen["none"][0][0]) == TINY["eval_episodes"]


def test_evaluation_leaves_the_learner_unchanged():
    world = WorldConfig()
    learner = make_learner("linear_q", "fsr", {"epsilon": 0.5}, world=world, seed=3)
    env = MediatedInteractionEnv("target", world)
    obs, _ = env.reset(seed=0)
    for _ in range(300):  # some learning, so the greedy policy is not trivial
        action = learner.act(obs)
        next_obs, reward, terminated, truncated, _ = env.step(action)
        learner.observe(obs, action, reward, next_obs, terminated)
        obs = next_obs
        if terminated or truncated:
            learner.end_episode()
            obs, _ = env.reset()
    before = {k: np.array(v, copy=True) for k, v in learner.state_dict().items()}
    tasks = sample_tasks("target", 4, np.random.default_rng(0), world)
    eval_env = MediatedInteractionEnv("target", world)
    first = evaluate(learner, eval_env, tasks, seed=11)
    assert evaluate(learner, eval_env, tasks, seed=11) == first
    after = learner.state_dict()
    assert before.keys() == after.keys()
    for key in before:
        np.testing.assert_array_equal(before[key], np.asarray(after[key]), err_msg=key)


@pytest.mark.parametrize("changes, message", [
    ({"n_source": 500, "strategy": "regular"}, "exceeds source_pool_size=200"),
    ({"budget": 601}, "not divisible into scale.eval_points=3"),
    ({"strategy": "curriculum", "n_source": 3}, "allowed: none, regular, scaffolded"),
    ({"strategy": "none", "n_source": 15}, "'none' needs n_source=0"),
    ({"strategy": "regular", "n_source": 0}, "need n_source >= 1"),
    ({"algorithm": "dqn", "representation": "rbf"}, "allowed: network"),
    ({"algorithm": "sarsa"}, "algorithm=sarsa is unknown; allowed: dqn, linear_q, sb3_dqn, sb3_ppo"),
    ({"algorithm_params": {"gamma": 1.5}}, "gamma"),
    ({"algorithm_params": {"lamda": 0.5}}, "unknown key(s) lamda"),
])
def test_bad_input_fails_before_any_work(monkeypatch, changes, message):
    def no_work(*args, **kwargs):
        raise AssertionError("work started before the input was checked")

    monkeypatch.setattr(recorder_module, "source_task_set", no_work)
    monkeypatch.setattr(PaperWorld, "make_env", no_work)  # every loop makes its environments here
    spec = replace(RunSpec(**TINY), **changes)
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        execute_run(spec)


def test_spec_from_dict_names_unknown_keys():
    with pytest.raises(ValueError, match=r"run: unknown key\(s\) budgett \(did you mean 'run.budget' for budgett\?\); allowed: algorithm,"):
        spec_from_dict({"budgett": 10})
    with pytest.raises(ValueError, match=r"env: unknown key\(s\) goal_radiuss \(did you mean 'env.goal_radius' for goal_radiuss\?\); allowed: interaction_radius,"):
        spec_from_dict({"world": {"goal_radiuss": 2.0}})
    spec = spec_from_dict({"world": {"goal_radius": 3.0}, "seed": 4})
    assert spec.world.goal_radius == 3.0 and spec.seed == 4


def test_bench_command_accepts_no_parts_and_refuses_unknown_ones(monkeypatch):
    from mediated_transfer.bench import __main__ as bench

    ran = []
    monkeypatch.setattr(bench.importlib, "import_module",
                        lambda name: type("M", (), {"run": staticmethod(lambda steps: ran.append((name, steps)))}))
    assert bench.main([]) == 0
    assert [name for name, _ in ran] == list(bench.PARTS.values())
    with pytest.raises(SystemExit):
        bench.main(["gpu"])


def test_the_callbacks_see_each_evaluation_point_and_the_trained_learner():
    spec = RunSpec(representation="fsr", seed=2, **TINY)
    seen, learners = [], []
    result = execute_run(spec, on_evaluation=lambda *point: seen.append(point),
                         on_finish=learners.append)
    assert seen == list(zip(result.steps, result.mean_reward, result.success_rate))
    [learner] = learners
    assert learner.stats == result.learner_stats
    # Watching does not change the run.
    assert execute_run(spec).mean_reward == result.mean_reward
