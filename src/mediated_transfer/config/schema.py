"""The structured configs behind conf/: what Hydra checks while it composes.

One place per default, by kind:

- The world and the learners are used from Python as well (``gymnasium.make``, tests, the
  bench), so their dataclasses hold the defaults and explain them in field docstrings:
  ``WorldConfig`` (env/config.py), ``LinearQConfig`` (learners/linear_q.py), ``RBFConfig``
  (learners/rbf.py), ``FSRConfig`` (learners/fsr.py), ``DQNConfig`` (learners/dqn_config.py),
  ``SB3PPOConfig`` and ``SB3DQNConfig`` (learners/sb3.py). They are
  the options of the groups ``env``, ``algorithm`` and ``representation`` (registered below;
  there are no YAML copies of them). conf/env/*.yaml are further ``env`` options, the readings
  of the world the paper leaves open: each extends ``default`` and sets only what it changes.
- The experiment's plumbing (scales, paths, tracking, the root keys, table reports) exists only
  for the command line, so its values and their comments live in conf/*.yaml; the dataclasses
  here give their keys and types only.

Hydra refuses a wrong type (``env.goal_radius=abc``) and an unknown key while composing;
ranges and pairings are checked by the dataclasses and RunSpec.validate.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

from hydra.core.config_store import ConfigStore
from omegaconf import MISSING, DictConfig, OmegaConf

from ..env.config import WorldConfig
from ..learners.dqn_config import DQNConfig
from ..learners.fsr import FSRConfig
from ..learners.linear_q import LinearQConfig
from ..learners.rbf import RBFConfig
from ..learners.sb3 import SB3DQNConfig, SB3PPOConfig

ROOT_SCHEMA = "run_schema"
"""Name of the root schema in the ConfigStore; conf/config.yaml lists it first."""


# --- the groups configured in Python: option name -> the dataclass with its defaults ----------
# A group option carries its own name (``algorithm.name``), which tables, folders and MLflow use,
# and its ``_target_``: what builds it (plugins.py), the same door a user's plugin comes through.


@dataclass(frozen=True)
class LinearQOption(LinearQConfig):
    """``algorithm=linear_q``: linear Q(lambda), the learner of Tables II and III."""

    name: str = "linear_q"
    _target_: str = "mediated_transfer.learners.linear_q.LinearQLearner.from_params"


@dataclass(frozen=True)
class DQNOption(DQNConfig):
    """``algorithm=dqn``: the deep Q-learner of Table IV (needs representation=network)."""

    name: str = "dqn"
    _target_: str = "mediated_transfer.learners.dqn.DQNLearner.from_params"


@dataclass(frozen=True)
class SB3PPOOption(SB3PPOConfig):
    """``algorithm=sb3_ppo``: Stable-Baselines3's PPO (representation network, rbf or fsr)."""

    name: str = "sb3_ppo"
    _target_: str = "mediated_transfer.learners.sb3.SB3Learner.ppo"


@dataclass(frozen=True)
class SB3DQNOption(SB3DQNConfig):
    """``algorithm=sb3_dqn``: Stable-Baselines3's DQN (representation network, rbf or fsr)."""

    name: str = "sb3_dqn"
    _target_: str = "mediated_transfer.learners.sb3.SB3Learner.dqn"


@dataclass(frozen=True)
class RBFOption(RBFConfig):
    """``representation=rbf``: 13829 Gaussian features (Table II)."""

    name: str = "rbf"
    _target_: str = "mediated_transfer.learners.rbf.RBFRepresentation.from_params"


@dataclass(frozen=True)
class FSROption(FSRConfig):
    """``representation=fsr``: 310 binary features (Table III)."""

    name: str = "fsr"
    _target_: str = "mediated_transfer.learners.fsr.FSRRepresentation.from_params"


@dataclass(frozen=True)
class NetworkOption:
    """``representation=network``: the network learns its own features from the sensor vector;
    its architecture keys are in ``algorithm`` (dqn: hidden_size, num_hidden_layers; sb3_ppo,
    sb3_dqn: net_arch)."""

    name: str = "network"
    _target_: Optional[str] = None
    """No feature map: the learner gets the sensor vector itself."""


@dataclass(frozen=True)
class WorldOption(WorldConfig):
    """``env=default``: the paper's world (env/paper.py), built through the world door
    (env/door.py) as a user's world is; conf/env/*.yaml extend it."""

    _target_: str = "mediated_transfer.env.paper.PaperWorld"


PYTHON_OPTIONS: dict[str, dict[str, type]] = {
    "env": {"default": WorldOption},
    "algorithm": {"linear_q": LinearQOption, "dqn": DQNOption, "sb3_ppo": SB3PPOOption,
                  "sb3_dqn": SB3DQNOption},
    "representation": {"rbf": RBFOption, "fsr": FSROption, "network": NetworkOption},
}


# --- the groups configured in YAML: keys and types only ---------------------------------------


@dataclass
class ScaleConfig:
    """conf/scale/*.yaml: how long and how often a run learns and is evaluated."""

    name: str = MISSING
    budget: int = MISSING
    eval_points: int = MISSING
    eval_episodes: int = MISSING
    seeds: int = MISSING
    reports_subdir: str = MISSING


@dataclass
class PathsConfig:
    """conf/paths/default.yaml: every output location."""

    root: str = MISSING
    multirun_dir: str = MISSING
    sweep_dir: str = MISSING
    runs_dir: str = MISSING
    reports_dir: str = MISSING
    cache_dir: str = MISSING
    mlflow_db: str = MISSING
    mlflow_artifacts: str = MISSING


@dataclass
class TrackingConfig:
    """conf/tracking/*.yaml: MLflow on or off, and where."""

    enabled: bool = MISSING
    uri: Optional[str] = MISSING
    artifact_location: Optional[str] = MISSING


@dataclass
class ReportConfig:
    """The ``report`` section of conf/experiment/*.yaml: which paper table a sweep reproduces
    (None: a table the paper does not have, e.g. Table V, reported without published values)."""

    paper_table: Optional[str] = MISSING
    title: str = MISSING
    figure: str = MISSING
    figure_title: str = MISSING


@dataclass
class LockstepConfig:
    runs: Optional[int] = MISSING
    device: str = MISSING


@dataclass
class RunConfig:
    """The root of conf/config.yaml: one learning run. Values and comments: conf/config.yaml."""

    name: str = MISSING
    cell: str = MISSING
    seed: int = MISSING
    threshold: float = MISSING
    source_pool_size: int = MISSING
    source_set_seed: int = MISSING
    threads_per_run: int = MISSING
    rerun_stale: bool = MISSING
    save_learner: bool = MISSING
    require_tuned: bool = MISSING
    lockstep: LockstepConfig = MISSING
    # A node with its _target_ (conf/strategy/*.yaml): the built-ins' parameters and a plugin's
    # own, so its keys are checked against its target's signature (plugins.py), not here.
    strategy: Any = MISSING
    n_source: int = MISSING
    paths: PathsConfig = MISSING
    scale: ScaleConfig = MISSING
    tracking: TrackingConfig = MISSING
    # Typed per option (PYTHON_OPTIONS): a field of a single dataclass type could not hold both
    # algorithms, and a frozen dataclass type here would make the node read-only.
    env: Any = MISSING
    algorithm: Any = MISSING
    representation: Any = MISSING
    report: Optional[ReportConfig] = None


def _option_node(cls: type) -> DictConfig:
    # The dataclasses are frozen (immutable value objects in Python); their Hydra nodes must
    # accept overrides, so the node is made writable. Its type still checks every value.
    node = OmegaConf.structured(cls)
    OmegaConf.set_readonly(node, False)
    if issubclass(cls, WorldConfig):
        # A world of one's own extends env=default with keys of its own (its config_class's):
        # the node takes them, and compose.check_known_keys checks every key against the
        # config_class of the node's _target_.
        OmegaConf.set_struct(node, False)
    return node


def register() -> None:
    """Put the root schema and the Python-configured group options into Hydra's ConfigStore."""
    store = ConfigStore.instance()
    store.store(name=ROOT_SCHEMA, node=RunConfig)
    for group, options in PYTHON_OPTIONS.items():
        for name, cls in options.items():
            store.store(group=group, name=name, node=_option_node(cls))


def register_n_source(values: list[int]) -> None:
    """Options ``n_source=<k>`` for any k >= 0 beyond the paper's (conf/n_source/*.yaml)."""
    store = ConfigStore.instance()
    for value in values:
        store.store(group="n_source", name=str(value), node={"n_source": value}, package="_global_")


def option_type(group: str, name: str) -> type | None:
    return PYTHON_OPTIONS.get(group, {}).get(name)


register()
