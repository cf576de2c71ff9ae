"""Build a learner from names and plain parameter dicts (what the Hydra groups hold).

``algorithm`` and ``representation`` are chosen independently on the command line, so invalid
pairs (dqn with rbf) and unknown keys are caught here, before any work starts, with messages
that name the allowed values.
"""

from __future__ import annotations

from typing import Any, Mapping

from ..config.mapping import config_from_mapping
from ..env.config import WorldConfig
from ..env.task import PICKING_LOCATIONS
from .base import Learner
from .dqn import DQNConfig, DQNLearner
from .fsr import FSRConfig, FSRRepresentation
from .linear_q import LinearQConfig, LinearQLearner
from .rbf import RBFConfig, RBFRepresentation

NUM_ACTIONS = len(PICKING_LOCATIONS) + 6  # 5 picks, 4 moves, 2 rotations

ALGORITHMS = ("linear_q", "dqn")
#: The representations each algorithm can learn on; the DQN learns its own features.
REPRESENTATIONS = {"linear_q": ("rbf", "fsr"), "dqn": ("network",)}

_ALGORITHM_CONFIGS = {"linear_q": LinearQConfig, "dqn": DQNConfig}
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
                f"algorithm.hidden_size / algorithm.num_hidden_layers); got {', '.join(extra)}"
            )
        rep_config = None
    else:
        rep_config = build_config(rep_cls, representation_params or {}, "representation")
    return algo_config, rep_config


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
    features = _REPRESENTATIONS[representation](rep_config)
    return LinearQLearner(algo_config, features, num_actions=NUM_ACTIONS, seed=seed)
