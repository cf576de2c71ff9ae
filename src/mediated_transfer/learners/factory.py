"""Build a learner from its group options (what the Hydra groups hold): each option's
``_target_`` builds it (plugins.py), a built-in's as a user's.

A learner's ``_target_`` is called as ``target(representation=<feature map or None>,
num_actions=<the world's>, seed=<the run's learner stream>, world=<the run's world, env/door.py>,
**algorithm keys)``; a representation's as ``target(**representation keys)`` (and
``sensors=<the world's sensor layout>`` if it takes it). ``algorithm`` and ``representation`` are
chosen independently on the command line, so invalid pairs (dqn with rbf: a learner's
``representations``) and unknown keys are caught here, before any work starts, with messages
that name the allowed values.
"""

from __future__ import annotations

import math
import os
from typing import Any, Mapping

from .. import plugins
from ..mapping import config_from_mapping
from ..env.sensors import PAPER_SENSORS
from ..env.task import PICKING_LOCATIONS
from ..env.config import WorldConfig
from .base import Learner
from .dqn_config import DQNConfig, layer_shapes
from .fsr import FSRConfig
from .linear_q import LinearQConfig
from .rbf import RBFConfig
from . import sb3

NUM_ACTIONS = len(PICKING_LOCATIONS) + 6  # 5 picks, 4 moves, 2 rotations

SB3_ALGORITHMS = sb3.ALGORITHMS
"""Stable-Baselines3's learners: they learn in SB3's own loop (run_sb3.py)."""
ALGORITHMS = ("linear_q", "dqn", *SB3_ALGORITHMS)
#: The representations each algorithm can learn on; the DQN learns its own features; SB3's
#: networks learn on the sensor vector itself (network) or on a representation's features.
REPRESENTATIONS = {"linear_q": ("rbf", "fsr"), "dqn": ("network",),
                   **{name: sb3.REPRESENTATIONS for name in SB3_ALGORITHMS}}
#: Where the architecture of a learner with representation=network is configured.
_ARCHITECTURE_KEYS = {"dqn": "algorithm.hidden_size / algorithm.num_hidden_layers",
                      **{name: "algorithm.net_arch" for name in SB3_ALGORITHMS}}

_ALGORITHM_CONFIGS = {"linear_q": LinearQConfig, "dqn": DQNConfig, **sb3.CONFIGS}
_REPRESENTATION_CONFIGS = {"rbf": RBFConfig, "fsr": FSRConfig, "network": None}


def build_config(cls, params: Mapping[str, Any], group: str):
    """The group's config object; ``name`` (the option's name in its Hydra group) is not a key."""
    return config_from_mapping(cls, {k: v for k, v in params.items() if k != "name"}, group)


def validate_learner_choice(
    algorithm: str,
    representation: str,
    algorithm_params: Mapping[str, Any] | None = None,
    representation_params: Mapping[str, Any] | None = None,
):
    """Check names, their pairing and every hyperparameter; return the two config objects."""
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm={algorithm!r} is unknown; allowed: {', '.join(ALGORITHMS)}")
    allowed = REPRESENTATIONS[algorithm]
    if representation not in allowed:
        raise ValueError(
            f"representation={representation!r} does not go with algorithm={algorithm}; "
            f"allowed: {', '.join(allowed)}"
        )
    algo_config = build_config(_ALGORITHM_CONFIGS[algorithm], plugins.without_target(algorithm_params or {}),
                               "algorithm")
    rep_cls = _REPRESENTATION_CONFIGS[representation]
    if rep_cls is None:
        extra = sorted(k for k in (representation_params or {}) if k not in ("name", "_target_"))
        if extra:
            raise ValueError(
                f"representation={representation} takes no keys (its architecture is in "
                f"{_ARCHITECTURE_KEYS[algorithm]}); got {', '.join(extra)}"
            )
        rep_config = None
    else:
        rep_config = build_config(rep_cls, plugins.without_target(representation_params or {}), "representation")
    return algo_config, rep_config


def memory_bytes(algorithm: str, algo_config, rep_config, world=None) -> int:
    """Estimated bytes of a learner's largest arrays (from the configs alone, nothing allocated),
    for the world's sensor layout and actions (``world``: a world of the door; None: the paper's)."""
    sensors = getattr(world, "sensors", PAPER_SENSORS)
    num_actions = getattr(world, "num_actions", NUM_ACTIONS)
    if algorithm in SB3_ALGORITHMS:
        return sb3.memory_bytes(algorithm, algo_config, _num_features(rep_config, sensors), sensors.size, num_actions)
    if algorithm == "dqn":
        c = algo_config
        # layer_shapes' first, one repeated and last layer: a list of 10^12 layers would not fit.
        first, *rest = layer_shapes(c.hidden_size, 1, num_actions, sensors)
        params = first[0] * (first[1] + 1) + (c.num_hidden_layers - 1) * c.hidden_size * (c.hidden_size + 1)
        params += rest[-1][0] * (rest[-1][1] + 1)
        # float32: the replay buffer and its batch; weights, target weights, gradient and
        # Adam's two moments; the batch's activations (forward and backward).
        from .dqn import ReplayBuffer  # torch: only where a DQN is asked for

        rows = (c.buffer_size + c.batch_size) * ReplayBuffer.layout(sensors.size)["WIDTH"]
        activations = 2 * c.batch_size * c.hidden_size * c.num_hidden_layers
        return 4 * (rows + 5 * params + activations)
    if isinstance(rep_config, RBFConfig):
        features = _gaussians(rep_config, sensors)
        # float64 weights per action, and three (index, value) buffers of every feature (an
        # RBF state may activate all of them).
        return features * (8 * num_actions + 3 * 16)
    features = sensors.num_distances * rep_config.distance_bins
    return features * 8 * num_actions


def _gaussians(rep_config: RBFConfig, sensors) -> int:
    """The RBF grid's size: each distance gets its kind's bins + 1 centres (rbf.py)."""
    bins = {"target": rep_config.tool_target_bins, "origin": rep_config.tool_origin_bins}
    return math.prod(bins[kind] + 1 for kind in sensors.kinds)


def _num_features(rep_config, sensors=PAPER_SENSORS) -> int:
    """Length of the feature vector of a representation's config (None: the sensor vector)."""
    if rep_config is None:
        return sensors.size
    if isinstance(rep_config, RBFConfig):
        return _gaussians(rep_config, sensors) + len(sensors.picking_locations)
    return sensors.num_distances * rep_config.distance_bins + 2 * len(sensors.picking_locations)


def check_memory(algorithm: str, algo_config, rep_config, world=None) -> None:
    """ValueError naming the size key if the learner cannot fit in this machine's memory."""
    needed = memory_bytes(algorithm, algo_config, rep_config, world)
    total = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    if needed > total:
        keys = {"dqn": "algorithm.buffer_size, algorithm.batch_size, algorithm.hidden_size, "
                       "algorithm.num_hidden_layers",
                "sb3_dqn": "algorithm.buffer_size, algorithm.batch_size, algorithm.net_arch",
                "sb3_ppo": "algorithm.n_steps, algorithm.batch_size, algorithm.net_arch",
                "rbf": "representation.tool_target_bins, representation.tool_origin_bins",
                "fsr": "representation.distance_bins"}
        if algorithm in keys:
            kind = algorithm
        else:
            kind = "rbf" if isinstance(rep_config, RBFConfig) else "fsr"
        raise ValueError(
            f"the learner needs ~{_size(needed)} of memory, more than this machine's {_size(total)}: "
            f"reduce {keys[kind]} ({_sizes(kind, algo_config, rep_config)})"
        )


def _sizes(kind: str, algo_config, rep_config) -> str:
    config = algo_config if kind in ("dqn", *SB3_ALGORITHMS) else rep_config
    names = {"dqn": ("buffer_size", "batch_size", "hidden_size", "num_hidden_layers"),
             "sb3_dqn": ("buffer_size", "batch_size", "net_arch"),
             "sb3_ppo": ("n_steps", "batch_size", "net_arch"),
             "rbf": ("tool_target_bins", "tool_origin_bins"), "fsr": ("distance_bins",)}[kind]
    return ", ".join(f"{name}={getattr(config, name)}" for name in names)


def _size(n: float) -> str:
    for unit in ("B", "KB", "MB", "GB", "TB", "PB"):
        if n < 1024 or unit == "PB":
            return f"{n:.3g} {unit}"
        n /= 1024


LEARNER_METHODS = ("act", "observe", "end_episode", "divergence", "stats")
"""What the run loop calls on every learner (learners/base.py)."""
PROVIDED = ("representation", "num_actions", "seed", "world")
"""What the framework passes to a learner's ``_target_`` besides the group's keys."""


def learner_target(algorithm: str, target: str | None = None):
    """The callable that builds ``algorithm`` (its ``_target_``, or the built-in's of that name)."""
    return plugins.locate("algorithm", target or _builtin("algorithm", algorithm))


def own_run_loop(algorithm: str, target: str | None = None):
    """The run loop a learner brings (its class's ``run_loop``, a dotted path: docs/extending.md,
    "A learner with its own loop"), or None: it learns in the project's loop."""
    path = getattr(plugins.owner_class(learner_target(algorithm, target)), "run_loop", None)
    return None if path is None else plugins.locate("algorithm.run_loop", path)


def representation_target(representation: str, target: str | None = None):
    """The callable that builds ``representation``'s feature map; None: the sensor vector itself."""
    path = target or _builtin("representation", representation)
    return None if path is None else plugins.locate("representation", path)


def _builtin(group: str, name: str) -> str | None:
    from ..config.targets import builtin_target

    try:
        return builtin_target(group, name)
    except KeyError as error:
        raise ValueError(error.args[0]) from None


def check_learner(algorithm: str, representation: str, algorithm_params: Mapping[str, Any],
                  representation_params: Mapping[str, Any], algorithm_target: str | None = None,
                  representation_target_path: str | None = None, world=None) -> None:
    """Every check of a learner before any work: its target importable, its interface, its
    pairing with the representation, its keys (a built-in's values and memory too, for the
    ``world``'s sensors and actions; None: the paper's)."""
    target = learner_target(algorithm, algorithm_target)
    plugins.check_interface("algorithm", target, LEARNER_METHODS, "learner")
    allowed = getattr(plugins.owner_class(target), "representations", None)
    if allowed is not None and representation not in allowed:
        raise ValueError(f"representation={representation!r} does not go with algorithm={algorithm}; "
                         f"allowed: {', '.join(allowed)}")
    features = representation_target(representation, representation_target_path)
    if algorithm in ALGORITHMS and plugins.path_of(target) == plugins.path_of(learner_target(algorithm)):
        algo_config, rep_config = validate_learner_choice(algorithm, representation, algorithm_params,
                                                          representation_params)
        check_memory(algorithm, algo_config, rep_config, world)
        return
    plugins.check_parameters("algorithm", target, algorithm_params, PROVIDED)
    if features is not None:
        plugins.check_parameters("representation", features, representation_params, ("sensors",))
    elif representation_params:
        raise ValueError(f"representation={representation} takes no keys; got {', '.join(sorted(representation_params))}")


def make_learner(
    algorithm: str,
    representation: str,
    algorithm_params: Mapping[str, Any] | None = None,
    representation_params: Mapping[str, Any] | None = None,
    world=None,
    seed: int = 0,
    algorithm_target: str | None = None,
    representation_target_path: str | None = None,
) -> Learner:
    """A fresh learner for the world's sensor vector and actions (``world``: a world of the
    door, env/door.py; None: the paper's). SB3's learners here only act; run_sb3.py builds the
    one that learns, on its environment."""
    if not hasattr(world, "sensors"):  # None or a bare config: the paper's world of it
        from ..env.door import build_world

        world = build_world(None, world) if world is not None else build_world(None, WorldConfig())
    target = learner_target(algorithm, algorithm_target)
    features = make_features(representation, representation_params, representation_target_path, world.sensors)
    return plugins.call(target, plugins.without_target(algorithm_params or {}), representation=features,
                        num_actions=world.num_actions, seed=seed, world=world)


def make_features(representation: str, representation_params: Mapping[str, Any] | None = None,
                  target: str | None = None, sensors=None):
    """The feature map phi(s) of a representation option; None for ``network`` (no feature map).
    A representation whose target takes ``sensors`` gets the world's sensor layout (env/sensors.py)."""
    build = representation_target(representation, target)
    if build is None:
        return None
    params = plugins.without_target(representation_params or {})
    if sensors is not None and "sensors" in _parameters(build):
        return plugins.call(build, params, sensors=sensors)
    return plugins.call(build, params)


def _parameters(target) -> set[str]:
    import inspect

    try:
        return set(inspect.signature(target).parameters)
    except (TypeError, ValueError):
        return set()
