"""RunSpec: everything that defines one learning run, as plain values, and its checks (one
line naming the key, before any work starts). Below the run loops: they, the recorder and
provenance read it, and it reads none of them.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from . import metrics, plugins
from .config.finite import check_finite
from .env import WorldConfig
from .learners.factory import check_learner, learner_target
from .learners.factory import own_run_loop as learner_run_loop
from .transfer.strategy import METHODS, SOURCE_TASKS

MAX_STEPS = 10**9
"""Most learning steps, and most evaluation steps, of one run: the paper's runs take 500k and
12.5M; 10^9 is more than a day at this project's speeds. A larger value is refused, not run."""
MAX_SOURCE_POOL = 10**6
"""Most random source tasks clustered into C (the paper: 10^4); sampling and k-means on a
larger pool would take hours in the launcher before any run starts."""


_CONFIG_KEYS = {"budget": "scale.budget", "eval_points": "scale.eval_points", "eval_episodes": "scale.eval_episodes"}
"""RunSpec fields that a config holds under another key: messages name the key a user types."""


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
    """The world's config: the fields of its ``config_class`` (env/door.py), the ``env`` keys."""
    algorithm_params: dict[str, Any] = field(default_factory=dict)
    representation_params: dict[str, Any] = field(default_factory=dict)
    strategy_params: dict[str, Any] = field(default_factory=dict)
    """The strategy's own keys (conf/strategy/<name>.yaml beside _target_ and name)."""
    algorithm_target: str | None = None
    """Dotted path of what builds the learner (the option's ``_target_``); None: the built-in
    option of that name (results recorded before options carried their target)."""
    representation_target: str | None = None
    strategy_target: str | None = None
    world_target: str | None = None
    """Dotted path of the world class (the ``env`` option's ``_target_``); None: the paper's."""

    def validate(self) -> "RunSpec":
        """Raise a clear error for bad input before any work starts."""
        world = self.make_world()  # the world's class and keys first: the checks below read it
        check_finite((("algorithm", self.algorithm, self.algorithm_params),
                      ("representation", self.representation, self.representation_params),
                      ("strategy", self.strategy, self.strategy_params),
                      ("env", None, asdict(self.world)),
                      ("", None, {"threshold": self.threshold})))
        check_learner(self.algorithm, self.representation, self.algorithm_params, self.representation_params,
                      self.algorithm_target, self.representation_target, world)
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
            world.check_room(scenario)
        return self

    def make_world(self):
        """The run's world (env/door.py): what its loops, evaluation and animation make
        environments, tasks and sensor layouts from."""
        from .env.door import build_world, world_class

        config_class = world_class(self.world_target).config_class
        if not isinstance(self.world, config_class):
            raise ValueError(f"env: {type(self.world).__name__} is not the config of "
                             f"{self.world_target or 'the paper world'} ({config_class.__name__})")
        return build_world(self.world_target, self.world)

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
        n_envs = self.algorithm_params.get("n_envs", 1)
        if n_envs != 1 and not hasattr(plugins.owner_class(target), "max_in_flight"):
            # Several environments (run_sb3.py): episodes begin before earlier ones are reported.
            raise ValueError(f"algorithm.n_envs={n_envs} keeps {n_envs} episodes in flight, but "
                             f"strategy={self.strategy} hears one episode at a time (it has no "
                             "max_in_flight); use algorithm.n_envs=1, or strategy=none, regular, scaffolded")
        signals = tuple(getattr(plugins.owner_class(target), "signals", ()) or ())
        if "td_error" in signals:  # only the project's own loop computes them (the learner's td_error)
            learner = plugins.owner_class(learner_target(self.algorithm, self.algorithm_target))
            if learner_run_loop(self.algorithm, self.algorithm_target) is not None or not callable(getattr(learner, "td_error", None)):
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
