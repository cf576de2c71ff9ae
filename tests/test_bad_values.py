"""Every config value is refused before any work, in one line naming the key, or accepted and run
to finite metrics; the environment refuses bad reset options and actions with one-line
ValueErrors. Property-based (hypothesis) over every numeric key of every group.

Composing with Hydra costs ~0.5 s, so the properties apply drawn values to a composed config
with ``OmegaConf.update`` (what Hydra does with a parsed override, with the same type checks);
a few tests go through ``compose_config`` itself for the command line's messages.
"""

from __future__ import annotations

import math
import string
from dataclasses import replace
from functools import lru_cache

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from omegaconf import OmegaConf
from omegaconf.errors import OmegaConfBaseException

from mediated_transfer.config.compose import ConfigError, compose_config
from mediated_transfer.config.spec import run_spec
from mediated_transfer.env.mediated_env import NUM_ACTIONS, MediatedInteractionEnv
from mediated_transfer.env.task import Task, sample_task
from mediated_transfer.learners.factory import make_learner, memory_bytes, validate_learner_choice
from mediated_transfer import metrics
from mediated_transfer.run import MAX_SOURCE_POOL, MAX_STEPS, RunSpec, execute_run

from .optional import DEEP, deep_option

LEARNERS = {
    "linear_q_rbf": ["algorithm=linear_q", "representation=rbf"],
    "linear_q_fsr": ["algorithm=linear_q", "representation=fsr"],
    "dqn": ["algorithm=dqn", "representation=network"],
    "sb3_ppo": ["algorithm=sb3_ppo", "representation=network"],
    "sb3_dqn": ["algorithm=sb3_dqn", "representation=network"],
}
BASE = ["scale=smoke", "tracking=none"]
GROUPS = ("env", "algorithm", "representation", "scale")
SMALL = dict(budget=200, eval_points=2, eval_episodes=2, source_pool_size=200)


@lru_cache(maxsize=None)
def composed(learner: str):
    return compose_config(LEARNERS[learner] + BASE)


def _numeric(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def numeric_keys(learner: str) -> list[str]:
    """Every numeric key of the composed config: root keys and those of every group."""
    cfg = OmegaConf.to_container(composed(learner), resolve=True)
    keys = [k for k, v in cfg.items() if _numeric(v)]
    keys += [f"{g}.{k}" for g in GROUPS for k, v in cfg[g].items() if _numeric(v)]
    return keys


# The learner-independent keys once (with linear_q/rbf), each learner's own keys with it.
KEYS = [("linear_q_rbf", k) for k in numeric_keys("linear_q_rbf")] + [
    (learner, k) for learner in ("linear_q_fsr", "dqn", "sb3_ppo", "sb3_dqn") for k in numeric_keys(learner)
    if k.startswith(("algorithm.", "representation."))
]

VALUES = st.one_of(
    st.sampled_from([-1, 0, 1, 2.5, 1e308, -1e308, math.nan, math.inf, -math.inf, 10**12, 10**30, "", "abc"]),
    st.integers(min_value=-(10**15), max_value=10**15),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(alphabet=string.ascii_letters + string.digits + ".-", max_size=6),
    st.booleans(),
)


def with_value(learner: str, key: str, value):
    """The composed config with ``key`` set to ``value`` as an override would set it."""
    cfg = composed(learner).copy()
    if key == "n_source" and _numeric(value) and value != 0:
        OmegaConf.update(cfg, "strategy", "regular")  # N_source >= 1 needs a transfer strategy
    OmegaConf.update(cfg, key, value, merge=True)
    return cfg


def check(learner: str, key: str, value) -> RunSpec | None:
    """The spec if ``key=value`` is accepted; None if refused in one line naming the key."""
    name = key.rpartition(".")[2]
    try:
        cfg = with_value(learner, key, value)
    except OmegaConfBaseException as error:  # the type (Hydra's message is condensed by compose)
        assert name in str(error)
        return None
    try:
        return run_spec(cfg)
    except ConfigError as error:
        message = str(error)
        assert "\n" not in message and name in message, (key, value, message)
        return None


def assert_cheaply_runnable(spec: RunSpec) -> None:
    """Bounded work, metrics that mean something, the env steps and the learner builds (when
    small): what a run does first."""
    assert spec.budget <= MAX_STEPS and spec.source_pool_size <= MAX_SOURCE_POOL
    assert spec.eval_points * spec.eval_episodes * spec.world.max_episode_steps <= MAX_STEPS
    # A curve that never earns a reward has not reached the threshold; a perfect one has.
    assert metrics.time_to_threshold([1, 2], [0.0, 0.0], spec.threshold) is None
    best = spec.world.success_reward
    assert metrics.time_to_threshold([1, 2], [best, best], spec.threshold) == 1
    assert math.isfinite(metrics.reward_loss([0.0] * spec.eval_points, best))
    env = MediatedInteractionEnv("target", spec.world)
    obs, _ = env.reset(seed=0)
    for action in range(NUM_ACTIONS):
        obs, reward, terminated, truncated, _ = env.step(action)
        assert np.all(np.isfinite(obs)) and math.isfinite(reward)
        if terminated or truncated:
            obs, _ = env.reset()
    configs = validate_learner_choice(spec.algorithm, spec.representation,
                                      spec.algorithm_params, spec.representation_params)
    if memory_bytes(spec.algorithm, *configs) < 200e6:
        learner = make_learner(spec.algorithm, spec.representation, spec.algorithm_params,
                               spec.representation_params, world=spec.world)
        assert 0 <= learner.act(obs, explore=False) < NUM_ACTIONS


def tiny(spec: RunSpec, key: str) -> RunSpec:
    """``spec`` at smoke size, except for the key under test."""
    name = key.rpartition(".")[2]
    return replace(spec, **{k: v for k, v in SMALL.items() if k != name})


def assert_finite_result(spec: RunSpec) -> None:
    result = execute_run(spec)
    assert len(result.mean_reward) == spec.eval_points
    assert all(0 <= r <= spec.world.success_reward for r in result.mean_reward)
    assert math.isfinite(result.reward_loss)
    # Time to threshold is a step of the curve where <R> is at least the threshold, or None.
    if result.time_to_threshold is not None:
        at = result.steps.index(result.time_to_threshold)
        assert min(result.mean_reward[at:]) >= spec.threshold - 1e-9


# derandomize: the same examples on every run, so a CI result is reproducible.
@pytest.mark.slow
@settings(max_examples=600, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from([k for k in KEYS if DEEP or not deep_option(k[0])]), VALUES)
def test_every_numeric_value_is_refused_in_one_line_or_runs(learner_key, value):
    learner, key = learner_key
    spec = check(learner, key, value)
    if spec is not None:
        assert_cheaply_runnable(tiny(spec, key))


def _edge_values(default):
    """Accepted-looking values away from the default, the first accepted one is run."""
    if isinstance(default, int):
        return [default * 2, default + 1, max(default // 2, 1), 1, 0]
    return [default * 2, default / 2, default + 1, 1.0, 0.0]


@pytest.mark.parametrize("learner, key", KEYS, ids=[f"{learner}:{key}" for learner, key in KEYS])
def test_each_key_runs_a_tiny_run_at_an_accepted_edge(learner, key):
    default = OmegaConf.select(composed(learner), key)
    for value in _edge_values(default):
        spec = check(learner, key, value)
        if spec is not None and value != default:
            assert_finite_result(tiny(spec, key))
            return
    pytest.skip(f"{key}: no accepted value other than the default among {_edge_values(default)}")


# --- the command line's path: Hydra's condensed messages and RunSpec's --------------------------


@pytest.mark.parametrize("override, named", [
    ("env.goal_radius=abc", "env.goal_radius=abc"),
    ("env.substeps=2.5", "env.substeps=2.5"),
    ("scale.budget=", "scale.budget="),
    ("scale.budget=10000000000", "scale.budget=10000000000"),
    # The scale's keys are named as typed (RunSpec calls them budget, eval_points, eval_episodes).
    ("scale.budget=-1", "scale.budget must be >= 1"),
    ("scale.eval_points=0", "scale.eval_points must be >= 1"),
    ("scale.eval_episodes=0", "scale.eval_episodes must be >= 1"),
    ("scale.budget=201", "scale.budget=201 is not divisible into scale.eval_points=2"),
    ("scale.eval_episodes=100000000", "scale.eval_episodes=100000000"),
    ("threshold=inf", "threshold"),
    ("threshold=nan", "threshold"),
    ("threshold=abc", "threshold=abc"),
    ("seed=-1", "seed"),
    ("n_source=-1", "n_source=-1"),
    ("threads_per_run=0", "threads_per_run"),
    ("lockstep.runs=0", "lockstep.runs"),
    ("lockstep.device=gpu", "lockstep.device"),
    ("lockstep.device=cuda", "lockstep.device=cuda"),  # the default learner is linear
    ("env.interaction_radius=2.5", "env.interaction_radius=2.5"),
])
def test_the_command_line_refuses_in_one_line(override, named):
    with pytest.raises(ConfigError) as caught:
        run_spec(compose_config(LEARNERS["linear_q_rbf"] + BASE + [override]))
    message = str(caught.value)
    assert "\n" not in message and named in message


def test_a_replay_buffer_beyond_memory_is_refused_with_its_size():
    with pytest.raises(ConfigError, match=r"buffer_size=1000000000000.*|memory.*buffer_size"):
        run_spec(with_value("dqn", "algorithm.buffer_size", 10**12))


# --- the environment: reset options and actions ----------------------------------------------------

COORDINATES = st.floats(allow_nan=True, allow_infinity=True) | st.integers(-100, 100) | st.integers()
TASKS = st.one_of(
    st.none(),
    st.builds(lambda seed: sample_task("target", np.random.default_rng(seed)), st.integers(0, 1000)),
    st.lists(COORDINATES, min_size=0, max_size=7),
    st.lists(st.floats(-30, 30), min_size=5, max_size=5),
    st.text(max_size=5),
    st.integers(),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)
OPTIONS = st.one_of(
    st.none(),
    st.fixed_dictionaries({"task": TASKS}),
    st.dictionaries(st.text(max_size=5), TASKS, max_size=2),
    st.lists(st.integers(), max_size=2),
    st.text(max_size=4),
    st.integers(),
)
ENV = MediatedInteractionEnv("target")


@settings(max_examples=300, deadline=None, derandomize=True)
@given(OPTIONS)
def test_reset_accepts_a_valid_task_or_refuses_in_one_line(options):
    try:
        obs, info = ENV.reset(seed=0, options=options)
    except ValueError as error:
        assert "\n" not in str(error)
        return
    assert ENV.observation_space.contains(obs)
    task = options.get("task") if isinstance(options, dict) else None
    if isinstance(task, Task):
        assert ENV._task == task


ACTIONS = st.one_of(
    st.integers(-(10**20), 10**20),
    st.integers(0, NUM_ACTIONS - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.none(),
    st.booleans(),
    st.text(max_size=3),
    st.integers(0, NUM_ACTIONS - 1).map(np.int64),
    st.integers(0, NUM_ACTIONS - 1).map(lambda a: np.array([a])),
)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.lists(ACTIONS, min_size=1, max_size=5))
def test_step_takes_an_action_index_or_refuses_in_one_line(actions):
    ENV.reset(seed=1)
    for action in actions:
        valid = isinstance(action, (int, np.integer)) and not isinstance(action, bool) \
            and 0 <= action < NUM_ACTIONS
        if not valid:
            with pytest.raises(ValueError) as caught:
                ENV.step(action)
            assert "\n" not in str(caught.value) and f"[0, {NUM_ACTIONS})" in str(caught.value)
            continue
        obs, reward, terminated, truncated, _ = ENV.step(action)
        assert ENV.observation_space.contains(obs) and reward in (0.0, ENV.config.success_reward)
        if terminated or truncated:
            ENV.reset()


@pytest.mark.parametrize("flags", [["-m", "--cfg", "job"], ["--info", "--cfg", "job"]])
def test_hydra_modes_given_together_are_refused_in_one_line(flags, tmp_path):
    """Hydra runs one mode (a sweep, printing a config, its info) and refuses two with a
    traceback; the entry point says which flags clash before anything runs."""
    from mediated_transfer.app import cli

    with pytest.raises(SystemExit) as stopped:
        cli([*flags, "scale=smoke", f"paths.root={tmp_path}"])
    message = str(stopped.value)
    assert message.startswith("Invalid configuration: ") and "cannot be combined" in message
    assert "\n" not in message and not list(tmp_path.iterdir())


def test_an_experiment_registered_on_tuned_values_refuses_a_learner_without_them(tmp_path):
    """Table V (PPO) is registered on Table I's tuned PPO values: a learner without them (here
    SB3's DQN, never tuned) does not start (require_tuned), in one line, before any folder; PPO,
    with its tuned file, starts."""
    from mediated_transfer.sweep import _check_tuned

    from mediated_transfer.config.compose import compose_config as compose

    untuned = ["experiment=table5_ppo", "algorithm=sb3_dqn", "scale=smoke", f"paths.root={tmp_path}"]
    with pytest.raises(ConfigError, match=r"require_tuned=true \(table5_ppo\): none \(no tuned file "
                                          r"sb3_dqn_network.yaml\)"):
        _check_tuned(compose(untuned, hydra=True))
    _check_tuned(compose([*untuned, "require_tuned=false"], hydra=True))
    _check_tuned(compose(["experiment=table5_ppo", "scale=smoke"], hydra=True))  # tuned PPO (Table I)
    _check_tuned(compose(["experiment=table4_dnn", "require_tuned=true", "scale=smoke"], hydra=True))  # tuned DQN
    assert not list(tmp_path.iterdir())
