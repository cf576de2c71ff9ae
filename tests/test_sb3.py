"""algorithm=sb3_ppo and sb3_dqn: Stable-Baselines3 through the project's strategies (on the
TransferWrapper), evaluation, results, MLflow runs and tables."""

from __future__ import annotations

import math
import numpy as np
import pytest

from .optional import importorskip

torch = importorskip("torch")
importorskip("stable_baselines3")

from mediated_transfer import run_sb3
from mediated_transfer.config.compose import ConfigError, compose_config
from mediated_transfer.config.spec import run_spec
from mediated_transfer.env.mediated_env import MediatedInteractionEnv
from mediated_transfer.learners.sb3 import SB3Learner
from mediated_transfer.reporting.__main__ import main as reporting_main
from mediated_transfer.run import RunSpec, RunStreams, execute_run
from mediated_transfer.saved_learner import greedy_policy
from mediated_transfer.sweep import tracking

from .test_sweep import _common, _results, _run_cli, _settings, root, source_cache  # noqa: F401

# Small enough to run in seconds, long enough for several PPO updates and DQN target syncs.
PARAMS = {"sb3_ppo": {"n_steps": 128, "batch_size": 32, "n_epochs": 2},
          "sb3_dqn": {"learning_starts": 50, "target_update_interval": 100}}
TINY = dict(budget=600, eval_points=3, eval_episodes=3, source_pool_size=200)


def spec(algorithm="sb3_ppo", representation="network", strategy="scaffolded", n_source=2, **changes):
    values = dict(algorithm=algorithm, representation=representation, strategy=strategy,
                  n_source=n_source, seed=4, algorithm_params=PARAMS[algorithm], **TINY)
    return RunSpec(**{**values, **changes})


@pytest.mark.parametrize("experiment, algorithm", [("table2_rbf", "sb3_ppo"), ("table4_dnn", "sb3_dqn")])
def test_a_smoke_sweep_writes_results_mlflow_runs_and_a_table(root, source_cache, experiment, algorithm):
    # The table's learner replaced by an SB3 one: a variant of the table (table2_rbf: the
    # networks see the RBF features; table4_dnn: the sensor vector itself).
    common = _common(root, source_cache)
    _run_cli(f"experiment={experiment}", f"algorithm={algorithm}", "cell=none_0,regular_1",
             "hydra/launcher=basic", *common)
    variant = f"algorithm={algorithm}"
    sweep_dir = root / "multirun" / experiment / "smoke"
    results = sorted(sweep_dir.glob(f"*/seed=*/{variant}/result.json"))
    assert [p.relative_to(sweep_dir).parts[:2] for p in results] == [("none_0", "seed=0"), ("regular_1", "seed=0")]
    assert not _results(sweep_dir)  # nothing in the baseline's folders

    assert reporting_main([f"experiment={experiment}", variant, *common]) == 0
    table = root / "reports" / "smoke" / "variants" / variant / f"{experiment}.md"
    assert "| 1/1 |" in table.read_text() and variant in table.read_text()

    settings = _settings(root)
    runs = tracking.find_runs(settings, experiment, f"tags.kind = 'run' and tags.variant = '{variant}'")
    assert sorted(r.data.tags["cell"] for r in runs) == ["none_0", "regular_1"]
    some = runs[0]
    assert some.data.params["algorithm.name"] == algorithm
    assert some.data.metrics["learning_steps_per_s"] > 0
    history = settings.client().get_metric_history(some.info.run_id, "mean_reward")
    assert sorted(m.step for m in history) == [100, 200]

    # The saved learner acts as the trained one: its greedy policy, back from learner.pt.
    folder = results[-1].parent
    policy, saved_spec = greedy_policy(folder)
    assert saved_spec.algorithm == algorithm
    obs, _ = MediatedInteractionEnv("target").reset(seed=1)
    assert policy(obs) in range(11)


@pytest.mark.parametrize("algorithm", ["sb3_ppo", "sb3_dqn"])
def test_same_spec_same_curve_and_the_run_loops_schedule(algorithm, tmp_path):
    first = execute_run(spec(algorithm, cache_dir=str(tmp_path)))
    second = execute_run(spec(algorithm, cache_dir=str(tmp_path)))
    assert first.steps == [200, 400, 600]  # the run loop's evaluation points
    assert first.learner_stats["learning_steps"] == 600  # stopped at the budget, not PPO's rollout end
    assert first.learner_stats["updates"] > 0
    for key in ("mean_reward", "success_rate", "source_phase_end", "source_tasks_solved",
                "first_target_reward_step", "learner_stats"):
        assert getattr(first, key) == getattr(second, key), key
    assert math.isfinite(first.reward_loss) and first.learning_steps_per_s > 0
    assert first.failure is None and first.code == {}  # the job writes the code version
    assert sum(first.choices["episodes"]) > 0 and first.choices["every"] == 200  # the one loop records them


def _final_policy(spec_) -> dict:
    saved = {}
    execute_run(spec_, on_finish=lambda learner: saved.update(learner.state_dict()["policy"]))
    return saved


def test_evaluation_does_not_change_what_is_learned(tmp_path):
    # Evaluation acts on its own environment with the deterministic policy: more evaluation
    # episodes leave the training environment, the generators and so the learning untouched.
    few = _final_policy(spec(cache_dir=str(tmp_path), eval_episodes=1))
    many = _final_policy(spec(cache_dir=str(tmp_path), eval_episodes=5))
    assert few.keys() == many.keys()
    assert all(torch.equal(few[k], many[k]) for k in few)


def test_the_training_env_starts_the_run_loops_first_target_task(monkeypatch):
    started = []

    class Recording(run_sb3._RecordedEpisodes):
        def reset(self, **kwargs):
            out = super().reset(**kwargs)
            started.append(self.unwrapped.task)
            return out

    monkeypatch.setattr(run_sb3, "_RecordedEpisodes", Recording)
    s = spec(strategy="none", n_source=0, budget=300, eval_points=1)
    execute_run(s)
    env = MediatedInteractionEnv("target")
    env.reset(seed=RunStreams.of(s).env_seed)  # what run.py's loop starts with
    assert started[0] == env.task


def test_a_diverged_policy_fails_the_run_with_its_reason(monkeypatch):
    class Diverging(SB3Learner):
        def act(self, observation, explore=True):
            with torch.no_grad():  # the first greedy action breaks the policy
                next(self.model.policy.parameters()).fill_(math.nan)
            return super().act(observation, explore)

    monkeypatch.setattr(run_sb3, "SB3Learner", Diverging)
    result = execute_run(spec(strategy="none", n_source=0))
    assert result.failed and result.failure.startswith("diverged by step 200: the policy's parameter")
    assert math.isnan(result.reward_loss) and result.steps == []


@pytest.mark.parametrize("overrides, message", [
    (["algorithm.net_arch=[64,0]"], "algorithm.net_arch must be a list of layer widths"),
    (["algorithm.batch_size=4096"], "algorithm.batch_size (4096) must be <= algorithm.n_steps"),
    (["algorithm.activation=gelu"], "algorithm.activation must be tanh or relu"),
    (["algorithm=sb3_dqn", "algorithm.buffer_size=1000000000000"], "memory"),
    (["algorithm=sb3_dqn", "algorithm.tau=0"], "algorithm.tau must be in (0, 1]"),
    (["algorithm=sb3_dqn", "representation=network", "+representation.foo=1"], "unknown key"),
])
def test_bad_sb3_settings_are_refused_in_one_line(overrides, message):
    with pytest.raises(ConfigError) as caught:
        run_spec(compose_config(["algorithm=sb3_ppo", "scale=smoke", "tracking=none", *overrides]))
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_every_representation_goes_with_the_sb3_learners():
    for representation, width in (("network", 11), ("rbf", 13829), ("fsr", 310)):
        cfg = compose_config(["algorithm=sb3_dqn", f"representation={representation}", "scale=smoke"])
        s = run_spec(cfg)
        learner = SB3Learner("sb3_dqn", *_configs(s))
        assert learner.model.policy.q_net.features_dim == width
        assert learner.act(np.ones(11) / 2, explore=False) in range(11)


def _configs(s: RunSpec):
    from mediated_transfer.learners.factory import make_features, validate_learner_choice

    algo, rep = validate_learner_choice(s.algorithm, s.representation, s.algorithm_params, s.representation_params)
    return algo, make_features(s.representation, s.representation_params)

