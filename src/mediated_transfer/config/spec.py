"""A composed config (or the resolved config a result recorded) as the RunSpec it runs."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import asdict
from typing import TYPE_CHECKING, Any

from omegaconf import DictConfig, OmegaConf

from .compose import ConfigError

if TYPE_CHECKING:
    from ..run import RunSpec


def spec_values(cfg: Mapping[str, Any]) -> dict[str, Any]:
    """The RunSpec fields of a composed config (DictConfig or its plain-dict form)."""
    algorithm = dict(_plain(cfg["algorithm"]))
    representation = dict(_plain(cfg["representation"]))
    scale = cfg["scale"]
    return {
        "algorithm": algorithm.pop("name"),
        "representation": representation.pop("name"),
        "strategy": cfg["strategy"],
        "n_source": cfg["n_source"],
        "seed": cfg["seed"],
        "budget": scale["budget"],
        "eval_points": scale["eval_points"],
        "eval_episodes": scale["eval_episodes"],
        "threshold": cfg["threshold"],
        "source_pool_size": cfg["source_pool_size"],
        "source_set_seed": cfg["source_set_seed"],
        "cache_dir": cfg["paths"]["cache_dir"],
        "world": dict(_plain(cfg["env"])),
        "algorithm_params": algorithm,
        "representation_params": representation,
    }


def run_spec(cfg: Mapping[str, Any]) -> "RunSpec":
    """The validated RunSpec of a config; ConfigError (one line) before any work if it cannot run."""
    # Imported here: the learners and the environment load only when a run is configured.
    from ..run import spec_from_dict

    try:
        return spec_from_dict(spec_values(cfg)).validate()
    except (ValueError, TypeError, KeyError) as error:
        raise ConfigError(str(error).strip("'\"")) from None


def comparable(spec: "RunSpec") -> dict[str, Any]:
    """What a run computes from: the spec without where source task sets are cached."""
    values = asdict(spec)
    values.pop("cache_dir")
    return values


def spec_digest(spec: "RunSpec") -> str:
    """Short digest of everything a run computes from (not where it caches)."""
    text = json.dumps(comparable(spec), sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def _plain(node: Any) -> Any:
    return OmegaConf.to_container(node, resolve=True) if isinstance(node, DictConfig) else node
