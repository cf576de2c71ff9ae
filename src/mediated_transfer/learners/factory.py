"""Build a learner from names and plain parameter dicts (what the Hydra groups hold).

``algorithm`` and ``representation`` are chosen independently on the command line, so invalid
pairs (dqn with rbf) and unknown keys are caught here, before any work starts, with messages
that name the allowed values.
"""

from __future__ import annotations

import os
from typing import Any, Mapping

from ..config.mapping import config_from_mapping
from ..env.config import WorldConfig
from ..env.task import NUM_DISTANCES, OBSERVATION_SIZE, PICKING_LOCATIONS
from .base import Learner
from .dqn import DQNConfig, DQNLearner, ReplayBuffer, layer_shapes
from .fsr import FSRConfig, FSRRepresentation
from .linear_q import LinearQConfig, LinearQLearner
from .rbf import RBFConfig, RBFRepresentation
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
_REPRESENTATIONS = {"rbf": RBFRepresentation, "fsr": FSRRepresentation}


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
    algo_config = build_config(_ALGORITHM_CONFIGS[algorithm], algorithm_params or {}, "algorithm")
    rep_cls = _REPRESENTATION_CONFIGS[representation]
    if rep_cls is None:
        extra = sorted(k for k in (representation_params or {}) if k != "name")
        if extra:
            raise ValueError(
                f"representation={representation} takes no keys (its architecture is in "
                f"{_ARCHITECTURE_KEYS[algorithm]}); got {', '.join(extra)}"
            )
        rep_config = None
    else:
        rep_config = build_config(rep_cls, representation_params or {}, "representation")
    return algo_config, rep_config


def memory_bytes(algorithm: str, algo_config, rep_config) -> int:
    """Estimated bytes of a learner's largest arrays (from the configs alone, nothing allocated)."""
    if algorithm in SB3_ALGORITHMS:
        return sb3.memory_bytes(algorithm, algo_config, _num_features(rep_config))
    if algorithm == "dqn":
        c = algo_config
        # layer_shapes' first, one repeated and last layer: a list of 10^12 layers would not fit.
        first, *rest = layer_shapes(c.hidden_size, 1, NUM_ACTIONS)
        params = first[0] * (first[1] + 1) + (c.num_hidden_layers - 1) * c.hidden_size * (c.hidden_size + 1)
        params += rest[-1][0] * (rest[-1][1] + 1)
        # float32: the replay buffer and its batch; weights, target weights, gradient and
        # Adam's two moments; the batch's activations (forward and backward).
        rows = (c.buffer_size + c.batch_size) * ReplayBuffer.WIDTH
        activations = 2 * c.batch_size * c.hidden_size * c.num_hidden_layers
        return 4 * (rows + 5 * params + activations)
    if isinstance(rep_config, RBFConfig):
        r = rep_config
        features = (r.tool_target_bins + 1) ** 3 * (r.tool_origin_bins + 1) ** 3
        # float64 weights per action, and three (index, value) buffers of every feature (an
        # RBF state may activate all of them).
        return features * (8 * NUM_ACTIONS + 3 * 16)
    features = NUM_DISTANCES * rep_config.distance_bins
    return features * 8 * NUM_ACTIONS


def _num_features(rep_config) -> int:
    """Length of the feature vector of a representation's config (None: the sensor vector)."""
    if rep_config is None:
        return OBSERVATION_SIZE
    if isinstance(rep_config, RBFConfig):
        return (rep_config.tool_target_bins + 1) ** 3 * (rep_config.tool_origin_bins + 1) ** 3 + len(PICKING_LOCATIONS)
    return NUM_DISTANCES * rep_config.distance_bins + 2 * len(PICKING_LOCATIONS)


def check_memory(algorithm: str, algo_config, rep_config) -> None:
    """ValueError naming the size key if the learner cannot fit in this machine's memory."""
    needed = memory_bytes(algorithm, algo_config, rep_config)
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


def make_learner(
    algorithm: str,
    representation: str,
    algorithm_params: Mapping[str, Any] | None = None,
    representation_params: Mapping[str, Any] | None = None,
    world: WorldConfig | None = None,
    seed: int = 0,
) -> Learner:
    """A fresh learner for the 11-dim sensor vector and the 11 actions of the world."""
    algo_config, rep_config = validate_learner_choice(
        algorithm, representation, algorithm_params, representation_params
    )
    if algorithm == "dqn":
        return DQNLearner(algo_config, num_actions=NUM_ACTIONS, seed=seed)
    features = make_features(representation, rep_config)
    if algorithm in SB3_ALGORITHMS:
        # Acts only; run_sb3.py builds its own, on the environment it learns on.
        return sb3.SB3Learner(algorithm, algo_config, features, world=world, seed=seed)
    return LinearQLearner(algo_config, features, num_actions=NUM_ACTIONS, seed=seed)


def make_features(representation: str, rep_config):
    """The feature map phi(s) of a representation's config; None for ``network`` (no config)."""
    return None if rep_config is None else _REPRESENTATIONS[representation](rep_config)
