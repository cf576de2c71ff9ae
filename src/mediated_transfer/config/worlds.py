"""The named readings of the world, the options of the group ``env``, as WorldConfig values.

``env=default`` is the WorldConfig dataclass itself (config/schema.py); every other option is a
file conf/env/<name>.yaml that extends it and changes one reading the paper leaves open (its
comment says which and why). Python callers, e.g. an analysis over a sweep of them, get the
same worlds a run of ``env=<name>`` gets.
"""

from __future__ import annotations

from ..env.config import WorldConfig
from .compose import CONF_DIR


def env_options() -> list[str]:
    """Names of the ``env`` options: ``default``, then conf/env/*.yaml in alphabetical order."""
    return ["default", *sorted(p.stem for p in (CONF_DIR / "env").glob("*.yaml"))]


def named_world(option: str = "default") -> WorldConfig:
    """The world of ``env=<option>``, composed by Hydra as a run composes it; ConfigError (one
    line, listing the options) for an unknown name."""
    from ..env.door import world_of_option

    return world_of_option(option).config
