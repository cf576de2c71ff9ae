"""One learning run of one configuration: source tasks first, then the target task, evaluated.

This is the experiment of section V: a learner is seeded by solving the source tasks C that a
transfer strategy hands out (those episodes are learning steps too), then learns the target
task until the budget is spent. At evenly spaced points the greedy policy is evaluated on a
fixed set of target tasks; from that curve come the reward loss L_R and the time to threshold.

The loop is written per run but keeps the pieces separate (strategy, learner, environment,
evaluation), so that several seeds of one table cell can later be stepped side by side. What
does not depend on who steps the learner (the seed's streams, the evaluation points, the result)
is shared with run_sb3.py, where Stable-Baselines3's learners learn in SB3's own loop.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from . import metrics, plugins
from .env import WorldConfig, sample_tasks
from .env.mediated_env import MediatedInteractionEnv
from .env.task import check_room
from .learners.base import Learner
from .learners.factory import check_learner, learner_target, make_learner
from .provenance import RESULTS_FORMAT, code_version
from .results import RunResult
from .transfer.source_tasks import source_task_set
from .transfer.choices import EpisodeChoices
from .transfer.strategy import (METHODS, SOURCE_TASKS, EpisodeOutcome, Strategy, StrategyContext, solved_count,
                                start_episode, wants_td_error)

# Independent random streams of one run, all derived from its seed (never the seed itself:
# default_rng(seed) is also the source pool's stream when seed == source_set_seed).
_ENV_STREAM, _STRATEGY_STREAM, _EVAL_TASK_STREAM, _EVAL_NOISE_STREAM, _LEARNER_STREAM = 1, 2, 3, 4, 5


MAX_STEPS = 10**9
"""Most learning steps, and most evaluation steps, of one run: the paper's runs take 500k and
12.5M; 10^9 is more than a day at this project's speeds. A larger value is refused, not run."""
MAX_SOURCE_POOL = 10**6
"""Most random source tasks clustered into C (the paper: 10^4); sampling and k-means on a
larger pool would take hours in the launcher before any run starts."""


_CONFIG_KEYS = {"budget": "scale.budget", "eval_points": "scale.eval_points", "eval_episodes": "scale.eval_episodes"}
"""RunSpec fields that a config holds under another key: messages name the key a user types."""


def _stream_seed(seed: int, stream: int) -> int:
    return int(np.random.SeedSequence([seed, stream]).generate_state(1)[0])


@dataclass(frozen=True)
class RunSpec:
    """Everything that defines one learning run, as plain values."""

    algorithm: str = "linear_q"
    """Learner: an option of the ``algorithm`` group (linear_q, dqn, sb3_ppo, sb3_dqn, a plugin's)."""
    representation: str = "rbf"
    """Its representation: rbf or fsr for linear_q, network for dqn."""
    strategy: str = "none"
    """Transfer strategy: none, regular (Algorithm 1), scaffolded (Algorithm 2), a plugin's."""
    n_source: int = 0
    """N_source: size of the clustered source task set C (0: no source phase)."""
    seed: int = 0
    budget: int = 500_000
    """Learning steps of the whole run, source and target episodes together."""
    eval_points: int = 25
    """Evaluation points, evenly spaced: after budget/eval_points, 2*budget/eval_points, ... steps."""
    eval_episodes: int = 100
    """Target-task episodes per evaluation point (greedy policy, action noise on)."""
    threshold: float = 8.0
    """<R> of an 80 % success rate (reward 10)."""
    source_pool_size: int = 10_000
    """Random source tasks clustered into C."""
    source_set_seed: int = 0
    """Seed of that pool: one fixed C per N_source, shared by all runs (as in the paper)."""
    cache_dir: str | None = None
    """Where clustered source task sets are cached (None: no cache)."""
    world: WorldConfig = field(default_factory=WorldConfig)
    algorithm_params: dict[str, Any] = field(default_factory=dict)
    representation_params: dict[str, Any] = field(default_factory=dict)
    strategy_params: dict[str, Any] = field(default_factory=dict)
    """The strategy's own keys (conf/strategy/<name>.yaml beside _target_ and name)."""
    algorithm_target: str | None = None
    """Dotted path of what builds the learner (the option's ``_target_``); None: the built-in
    option of that name (results recorded before options carried their target)."""
    representation_target: str | None = None
    strategy_target: str | None = None

    def validate(self) -> "RunSpec":
        """Raise a clear error for bad input before any work starts."""
        from .config.finite import check_finite

        check_finite(self)
        check_learner(self.algorithm, self.representation, self.algorithm_params, self.representation_params,
                      self.algorithm_target, self.representation_target)
        self._check_strategy()
        # Values from Python or a recorded result.json are not typed by Hydra: check them here.
        for key in ("seed", "n_source", "budget", "eval_points", "eval_episodes",
                    "source_pool_size", "source_set_seed"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise ValueError(f"{_CONFIG_KEYS.get(key, key)} must be an integer, got {value!r}")
        for key in ("seed", "n_source", "source_set_seed"):
            if getattr(self, key) < 0:
                raise ValueError(f"{key} must be >= 0, got {getattr(self, key)}")
        self._check_threshold()
        if self.source_pool_size < 1:
            raise ValueError(f"source_pool_size must be >= 1, got {self.source_pool_size}")
        if self.source_pool_size > MAX_SOURCE_POOL:
            raise ValueError(
                f"source_pool_size={self.source_pool_size} exceeds {MAX_SOURCE_POOL:,}: sampling "
                "and clustering a larger pool would take hours before the first learning step"
            )
        if self.n_source > self.source_pool_size:
            raise ValueError(
                f"n_source={self.n_source} exceeds source_pool_size={self.source_pool_size}: "
                "cannot cluster a pool into more clusters than it has tasks"
            )
        needs = getattr(plugins.owner_class(self.strategy_class()), "source_tasks", "optional")
        if needs not in SOURCE_TASKS:
            raise ValueError(f"strategy={self.strategy}: its source_tasks attribute is {needs!r}; "
                             f"allowed: {', '.join(SOURCE_TASKS)}")
        if (needs == "none" and self.n_source) or (needs == "required" and not self.n_source):
            raise ValueError(
                f"strategy={self.strategy!r} with n_source={self.n_source}: 'none' needs "
                "n_source=0, and 'regular'/'scaffolded' (any strategy that learns source tasks of C) "
                "need n_source >= 1"
            )
        for key in ("budget", "eval_points", "eval_episodes"):
            if getattr(self, key) < 1:
                raise ValueError(f"scale.{key} must be >= 1, got {getattr(self, key)}")
        if self.budget % self.eval_points:
            raise ValueError(
                f"scale.budget={self.budget} is not divisible into scale.eval_points={self.eval_points} "
                "evenly spaced evaluation points"
            )
        self._check_work()
        # Sizes that leave no room for a task would make task sampling loop (almost) forever.
        for scenario in ("target", "source") if self.n_source else ("target",):
            check_room(scenario, self.world)
        return self

    def strategy_class(self):
        """What builds the strategy: its ``_target_`` (or the built-in's of its name)."""
        from .config.targets import builtin_target

        path = self.strategy_target
        if path is None:
            try:
                path = builtin_target("strategy", self.strategy)
            except KeyError as error:
                raise ValueError(error.args[0]) from None
        return plugins.locate("strategy", path)

    def _check_strategy(self) -> None:
        target = self.strategy_class()
        plugins.check_interface("strategy", target, METHODS, "strategy")
        plugins.check_parameters("strategy", target, self.strategy_params, ("context",))
        signals = tuple(getattr(plugins.owner_class(target), "signals", ()) or ())
        if "td_error" in signals:  # only the project's own loop computes them (the learner's td_error)
            learner = plugins.owner_class(learner_target(self.algorithm, self.algorithm_target))
            if own_run_loop(self) is not None or not callable(getattr(learner, "td_error", None)):
                raise ValueError(f"strategy={self.strategy} asks for the learner's TD errors, which "
                                 f"algorithm={self.algorithm} does not report (its own run loop, or no "
                                 "td_error method); use a learner of the project's loop (linear_q, dqn)")

    def _check_threshold(self) -> None:
        # <R> is a mean of episode rewards in {0, success_reward}: a threshold outside
        # (0, success_reward] (or nan) would be "reached" at the first point or never.
        # A threshold within the metric's round-off tolerance of 0 is reached by a zero curve.
        threshold, best = self.threshold, self.world.success_reward
        low = metrics.MetricsConfig().tolerance
        if isinstance(threshold, bool) or not isinstance(threshold, (int, float)) \
                or not low < threshold <= best:
            raise ValueError(
                f"threshold must be a number in ({low:g}, env.success_reward={best:g}], got {threshold!r}"
            )

    def _check_work(self) -> None:
        # A run far beyond any study's size would look like a hang: refuse it with its size.
        if self.budget > MAX_STEPS:
            raise ValueError(
                f"scale.budget={self.budget} exceeds {MAX_STEPS:,} learning steps (more than a day "
                "per run at this project's ~10^4 steps/s); split the study or raise run.MAX_STEPS"
            )
        # Evaluation may run every episode to its truncation: eval_points x eval_episodes x
        # max_episode_steps greedy steps.
        worst = self.eval_points * self.eval_episodes * self.world.max_episode_steps
        if worst > MAX_STEPS:
            raise ValueError(
                f"scale.eval_points={self.eval_points} x scale.eval_episodes={self.eval_episodes} x "
                f"env.max_episode_steps={self.world.max_episode_steps} = {worst} evaluation steps "
                f"exceeds {MAX_STEPS:,} (more than a day per run)"
            )

    def describe(self) -> str:
        return (f"{self.algorithm}/{self.representation} {self.strategy} "
                f"N_source={self.n_source} seed={self.seed}")


def evaluate(learner: Learner, env: MediatedInteractionEnv, tasks, seed: int) -> tuple[float, float]:
    """<R> and success rate of the greedy policy on ``tasks``; the learner is left unchanged."""
    total, successes = 0.0, 0
    for i, task in enumerate(tasks):
        # Re-seeding at every evaluation point gives every point the same noise stream start.
        obs, _ = env.reset(seed=seed if i == 0 else None, options={"task": task})
        while True:
            obs, reward, terminated, truncated, _ = env.step(learner.act(obs, explore=False))
            total += reward
            if terminated or truncated:
                successes += bool(terminated)
                break
    return total / len(tasks), successes / len(tasks)


ProgressFn = Callable[[int, int], None]
EvaluationFn = Callable[[int, float, float], None]
"""Called at each evaluation point with (learning step, <R>, success rate)."""
FinishFn = Callable[[Learner], None]
"""Called with the trained learner at the end of the run (e.g. to save it)."""


@dataclass
class RunStreams:
    """What a run draws from its seed, whichever loop drives its learner: each from its own
    stream, so that the strategy, the environment and the evaluation are the same for every
    learner of a seed."""

    learner_seed: int
    env_seed: int
    """Seed of the training environment's first reset (its target tasks and action noise)."""
    strategy: Strategy
    eval_tasks: list
    """The evaluation's target tasks: the same for every strategy and N_source of a seed."""
    eval_seed: int
    """Seed of the evaluation environment's action noise, at every evaluation point."""

    @classmethod
    def of(cls, spec: RunSpec) -> "RunStreams":
        world = spec.world
        context = StrategyContext(
            rng=np.random.default_rng(_stream_seed(spec.seed, _STRATEGY_STREAM)), world=world,
            n_source=spec.n_source,
            build_source_tasks=lambda: source_task_set(spec.n_source, world, pool_size=spec.source_pool_size,
                                                       seed=spec.source_set_seed, cache_dir=spec.cache_dir))
        strategy = plugins.call(spec.strategy_class(), spec.strategy_params, context=context)
        eval_tasks = sample_tasks("target", spec.eval_episodes,
                                  np.random.default_rng(_stream_seed(spec.seed, _EVAL_TASK_STREAM)), world)
        return cls(_stream_seed(spec.seed, _LEARNER_STREAM), _stream_seed(spec.seed, _ENV_STREAM),
                   strategy, eval_tasks, _stream_seed(spec.seed, _EVAL_NOISE_STREAM))


class Curve:
    """The run's evaluation points as it goes, the learning time between them (evaluation is
    not learning), and a divergence found at one of them."""

    def __init__(self, spec: RunSpec, streams: RunStreams, on_evaluation: EvaluationFn | None = None):
        self.every = spec.budget // spec.eval_points
        self.env = MediatedInteractionEnv("target", spec.world)
        self.tasks, self.seed, self.on_evaluation = streams.eval_tasks, streams.eval_seed, on_evaluation
        self.steps: list[int] = []
        self.rewards: list[float] = []
        self.success: list[float] = []
        self.failure: str | None = None
        self.learn_time = 0.0
        self.started = self._mark = time.perf_counter()

    def evaluate(self, step: int, learner) -> None:
        """Evaluate ``learner``'s greedy policy at learning ``step``, then check it for divergence."""
        self.learn_time += time.perf_counter() - self._mark
        r, p = evaluate(learner, self.env, self.tasks, self.seed)
        self.steps.append(step)
        self.rewards.append(r)
        self.success.append(p)
        if self.on_evaluation is not None:
            self.on_evaluation(step, r, p)
        self.check(step, learner)
        self._mark = time.perf_counter()

    def check(self, step: int, learner) -> None:
        """Record a divergence of ``learner`` found at learning ``step`` as the run's failure."""
        reason = learner.divergence()
        if reason is not None:  # the rest of the budget would only repeat it
            self.failure = f"diverged by step {step}: {reason}"

    def stop(self) -> float:
        """End the learning time; returns the run's wall time so far."""
        now = time.perf_counter()
        self.learn_time += now - self._mark
        self._mark = now
        return now - self.started


def execute_run(spec: RunSpec, progress: ProgressFn | None = None, progress_every: int = 0,
                on_evaluation: EvaluationFn | None = None,
                on_finish: FinishFn | None = None) -> RunResult:
    """Run one learning run and return its result (the caller writes it). The callbacks see
    the run as it goes; they cannot change what it computes."""
    spec.validate()
    own_loop = own_run_loop(spec)
    if own_loop is not None:  # e.g. SB3 learns in its own loop (run_sb3.py)
        return own_loop(spec, progress, progress_every, on_evaluation, on_finish)
    world = spec.world
    streams = RunStreams.of(spec)
    learner = make_learner(spec.algorithm, spec.representation, spec.algorithm_params,
                           spec.representation_params, world=world, seed=streams.learner_seed,
                           algorithm_target=spec.algorithm_target,
                           representation_target_path=spec.representation_target)
    strategy = streams.strategy
    td_signal = wants_td_error(strategy)
    env = MediatedInteractionEnv("target", world)
    curve = Curve(spec, streams, on_evaluation)
    choices = EpisodeChoices(curve.every, spec.eval_points, world.mediated_min_distance)
    progress_every = progress_every or curve.every

    source_phase_end: int | None = None
    first_target_reward: int | None = None
    step = 0
    env_seed: int | None = streams.env_seed
    while step < spec.budget and curve.failure is None:
        obs, _, task = start_episode(env, strategy, env_seed)
        env_seed, start = None, step
        terminated = False
        episode_return, length, td_total = 0.0, 0, 0.0
        while True:
            action = learner.act(obs, explore=True)
            next_obs, reward, terminated, truncated, _ = env.step(action)
            if td_signal:  # before observe: the error the update learns from
                td_total += abs(learner.td_error(obs, action, reward, next_obs, terminated))
            learner.observe(obs, action, reward, next_obs, terminated)
            obs = next_obs
            step += 1
            episode_return += reward
            length += 1
            if reward > 0 and task is None and first_target_reward is None:
                first_target_reward = step
            if step % curve.every == 0:
                curve.evaluate(step, learner)
            if progress is not None and step % progress_every == 0:
                progress(step, spec.budget)
            if terminated or truncated or step >= spec.budget or curve.failure is not None:
                break
        learner.end_episode()
        choices.add(start, task is None, (env.task if task is None else task).target_distance, bool(terminated))
        was_done = strategy.done
        strategy.report(EpisodeOutcome(task, bool(terminated), episode_return, length, step,
                                       td_total / length if td_signal else None))
        if not was_done and strategy.done:
            source_phase_end = step
    wall = curve.stop()
    if on_finish is not None:
        on_finish(learner)
    return run_result(spec, curve, strategy, learner.stats, source_phase_end, first_target_reward, wall,
                      choices.summary())


def own_run_loop(spec: RunSpec):
    """The run loop a learner brings (its class's ``run_loop``, a dotted path), or None: run.py's."""
    path = getattr(plugins.owner_class(learner_target(spec.algorithm, spec.algorithm_target)), "run_loop", None)
    return None if path is None else plugins.locate("algorithm.run_loop", path)


def run_result(spec: RunSpec, curve: Curve, strategy: Strategy, learner_stats: dict,
               source_phase_end: int | None, first_target_reward: int | None, wall: float,
               choices: dict | None = None) -> RunResult:
    """The RunResult of a finished (or failed) run (``choices``: transfer/choices.py, from the
    loops that record them)."""
    rewards_arr = np.asarray(curve.rewards)
    failure, world = curve.failure, spec.world
    # A failed run's partial curve has no reward loss or time to threshold: none is made up.
    return RunResult(
        algorithm=spec.algorithm,
        representation=spec.representation,
        strategy=spec.strategy,
        n_source=spec.n_source,
        seed=spec.seed,
        budget=spec.budget,
        steps=curve.steps,
        mean_reward=curve.rewards,
        success_rate=curve.success,
        reward_loss=math.nan if failure else metrics.reward_loss(rewards_arr, world.success_reward),
        time_to_threshold=None if failure else metrics.time_to_threshold(curve.steps, rewards_arr, spec.threshold),
        source_phase_end=source_phase_end,
        first_target_reward_step=first_target_reward,
        source_tasks_solved=solved_count(strategy),
        wall_time_s=wall,
        learning_steps_per_s=spec.budget / curve.learn_time if curve.learn_time > 0 else math.inf,
        learner_stats=dict(learner_stats),
        code=code_version(spec),
        results_format=RESULTS_FORMAT,
        failure=failure,
        choices=choices,
    )
