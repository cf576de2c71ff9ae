"""The named readings of the world, the options of the group ``env``, as WorldConfig values.

``env=default`` is the WorldConfig dataclass itself (config/schema.py); every other option is a
file conf/env/<name>.yaml that extends it and changes one reading the paper leaves open (its
comment says which and why). Python callers, e.g. an analysis over a sweep of them, get the
same worlds a run of ``env=<name>`` gets.
"""

from __future__ import annotations

from ..env.config import WorldConfig
from .compose import CONF_DIR, compose_config


def env_options() -> list[str]:
    """Names of the ``env`` options: ``default``, then conf/env/*.yaml in alphabetical order."""
    return ["default", *sorted(p.stem for p in (CONF_DIR / "env").glob("*.yaml"))]


def named_world(option: str = "default") -> WorldConfig:
    """The world of ``env=<option>``, composed by Hydra as a run composes it; ConfigError (one
    line, listing the options) for an unknown name."""
    return world_of_option(option).config


def world_of_option(option: str = "default", overrides=()):
    """The world of ``env=<option>``, composed by Hydra as a run composes it, with further
    ``overrides`` (``hydra.searchpath=[pkg://<package>.conf]`` for a plugin's option, env keys);
    ConfigError (one line, listing the options) for an unknown name."""
    return world_of_config(compose_config([f"env={option}", *overrides]))


def world_of_config(cfg):
    """The world of a composed config's ``env`` node (a study's, a run's), built by the door."""
    from omegaconf import OmegaConf

    from ..env.door import build_world, split_option, world_config

    target, values = split_option(OmegaConf.to_container(cfg.env, resolve=True))
    return build_world(target, world_config(target, values))
