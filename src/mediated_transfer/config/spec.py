"""A composed config (or the resolved config a result recorded) as the RunSpec it runs, and how
two runs' configs compare."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import asdict, replace
from typing import TYPE_CHECKING, Any

from omegaconf import DictConfig, OmegaConf

from .compose import ConfigError
from ..mapping import config_from_mapping

if TYPE_CHECKING:
    from ..runspec import RunSpec


def spec_values(cfg: Mapping[str, Any]) -> dict[str, Any]:
    """The RunSpec fields of a composed config (DictConfig or its plain-dict form)."""
    algorithm, algorithm_target, algorithm_params = _option(cfg["algorithm"])
    representation, representation_target, representation_params = _option(cfg["representation"])
    strategy, strategy_target, strategy_params = _option(cfg["strategy"])
    world = dict(_plain(cfg["env"]))
    world_target = world.pop("_target_", None)  # None: a result recorded before worlds had one
    scale = cfg["scale"]
    return {
        "algorithm": algorithm,
        "algorithm_target": algorithm_target,
        "representation": representation,
        "representation_target": representation_target,
        "strategy": strategy,
        "strategy_target": strategy_target,
        "strategy_params": strategy_params,
        "n_source": cfg["n_source"],
        "seed": cfg["seed"],
        "budget": scale["budget"],
        "eval_points": scale["eval_points"],
        "eval_episodes": scale["eval_episodes"],
        "threshold": cfg["threshold"],
        "source_pool_size": cfg["source_pool_size"],
        "source_set_seed": cfg["source_set_seed"],
        "cache_dir": cfg["paths"]["cache_dir"],
        "world": world,
        "world_target": world_target,
        "algorithm_params": algorithm_params,
        "representation_params": representation_params,
    }


def spec_from_dict(values: Mapping[str, Any]) -> "RunSpec":
    """A RunSpec from plain values (``spec_values``' or a saved learner's); unknown keys are errors."""
    # Imported here: the learners and the environment load only when a run is configured.
    from ..env.door import world_config
    from ..runspec import RunSpec

    values = dict(values)
    world = values.pop("world", None)
    spec = config_from_mapping(RunSpec, values, "run")
    if world is not None:  # the config of the world its _target_ names (the door's)
        spec = replace(spec, world=world_config(spec.world_target, world))
    return spec


def _option(node: Any) -> tuple[str, str | None, dict[str, Any]]:
    """(name, _target_, parameters) of a group's node; a result recorded before strategies were
    nodes holds the strategy's name alone (its target is then the built-in's of that name)."""
    if isinstance(node, str):
        return node, None, {}
    values = dict(_plain(node))
    name = values.pop("name")
    return name, values.pop("_target_", None), values


def run_spec(cfg: Mapping[str, Any]) -> "RunSpec":
    """The validated RunSpec of a config; ConfigError (one line) before any work if it cannot run."""
    try:
        _check_launch_keys(cfg)
        return spec_from_dict(spec_values(cfg)).validate()
    except (ValueError, TypeError, KeyError) as error:
        # str() of a KeyError is its quoted key; other messages may end in a quoted value.
        message = error.args[0] if isinstance(error, KeyError) and error.args else error
        raise ConfigError(str(message)) from None


MAX_THREADS = 1024
"""Most CPU threads per run (torch and BLAS refuse absurd counts, mid-run)."""
MAX_SEEDS = 10_000
"""Most seeds per table cell: a sweep lists every job before it starts."""


def _check_launch_keys(cfg: Mapping[str, Any]) -> None:
    # Keys a run uses outside its RunSpec: how many threads it may use, how many seeds a sweep
    # of an experiment has. A recorded result's config may lack them.
    bounds = {"threads_per_run": MAX_THREADS, "scale.seeds": MAX_SEEDS}
    for key, most in bounds.items():
        node, _, name = key.rpartition(".")
        section = cfg[node] if node else cfg
        if name not in section:
            continue
        value = section[name]
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= most:
            raise ValueError(f"{key} must be an integer in [1, {most}], got {value!r}")
    _check_lockstep(cfg)


def _check_lockstep(cfg: Mapping[str, Any]) -> None:
    from ..learners.factory import SB3_ALGORITHMS
    from ..lockstep.group import DEVICES

    if "lockstep" not in cfg:  # a result recorded before lockstep existed
        return
    runs, device = cfg["lockstep"]["runs"], cfg["lockstep"]["device"]
    if runs is not None and (isinstance(runs, bool) or not isinstance(runs, int) or not 1 <= runs <= MAX_SEEDS):
        raise ValueError(f"lockstep.runs must be null or an integer in [1, {MAX_SEEDS}], got {runs!r}")
    if device not in DEVICES:
        raise ValueError(f"lockstep.device must be one of {', '.join(DEVICES)}, got {device!r}")
    algorithm = cfg["algorithm"]["name"]
    if device != "cpu" and algorithm != "dqn":
        raise ValueError(f"lockstep.device={device} stacks deep Q-networks (algorithm=dqn); "
                         f"algorithm={algorithm} runs on the CPU (lockstep.device=cpu)")
    if algorithm in SB3_ALGORITHMS and runs not in (None, 1):
        raise ValueError(f"lockstep.runs={runs}: algorithm={algorithm} learns in Stable-Baselines3's "
                         "own loop, one run per process (lockstep.runs=1)")


def comparable(spec: "RunSpec") -> dict[str, Any]:
    """What a run computes from: the spec without where source task sets are cached and without
    the dotted paths of its code (which code computed a run is provenance's, not the config's:
    moving a class leaves the run the same run). A strategy without parameters adds no key, so
    runs recorded before strategies had parameters keep their identity."""
    values = asdict(spec)
    for key in ("cache_dir", "algorithm_target", "representation_target", "strategy_target", "world_target"):
        values.pop(key)
    if not values["strategy_params"]:
        values.pop("strategy_params")
    return values


def spec_digest(spec: "RunSpec") -> str:
    """Short digest of everything a run computes from (not where it caches)."""
    text = json.dumps(comparable(spec), sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def _plain(node: Any) -> Any:
    return OmegaConf.to_container(node, resolve=True) if isinstance(node, DictConfig) else node


def differences(stored: Mapping[str, Any], wanted: Mapping[str, Any],
                labels: tuple[str, str] = ("stored", "now")) -> str:
    """Every key of ``wanted`` where ``stored`` (two ``comparable`` configs) differs, one clause each
    (``algorithm_params.lambda_: stored 0.5, now 0.9``); "" when there is none."""
    differ = sorted(k for k in wanted if stored.get(k) != wanted[k])
    return "; ".join(_difference(k, stored.get(k), wanted.get(k), labels) for k in differ)


def _difference(key: str, stored: Any, wanted: Any, labels: tuple[str, str]) -> str:
    if isinstance(stored, dict) and isinstance(wanted, dict):
        keys = sorted(k for k in set(stored) | set(wanted) if stored.get(k) != wanted.get(k))
        return ", ".join(_difference(f"{key}.{k}", stored.get(k), wanted.get(k), labels) for k in keys)
    return f"{key}: {labels[0]} {stored!r}, {labels[1]} {wanted!r}"
