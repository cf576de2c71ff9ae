"""Which code builds a group's option: the ``_target_`` of the built-in options by name, for
runs recorded before options carried their target, and the options a group offers (conf/, the
Python-configured options, and every folder on ``hydra.searchpath``)."""

from __future__ import annotations

import functools
from pathlib import Path

from omegaconf import OmegaConf

from .compose import CONF_DIR, search_dirs
from .schema import PYTHON_OPTIONS


def builtin_target(group: str, name: str) -> str | None:
    return _builtin_target(group, name, tuple(search_dirs()))


@functools.lru_cache(maxsize=256)
def _builtin_target(group: str, name: str, searched: tuple[Path, ...]) -> str | None:
    """The ``_target_`` of option ``name`` of ``group`` (None: an option built by nothing, e.g.
    representation=network); KeyError naming the options if there is no such option."""
    if name in PYTHON_OPTIONS.get(group, {}):
        return getattr(PYTHON_OPTIONS[group][name], "_target_", None)
    for folder in (CONF_DIR, *searched):
        path = Path(folder) / group / f"{name}.yaml"
        if path.is_file():
            node = OmegaConf.load(path)
            return node.get("_target_")
    raise KeyError(f"{group}={name} is unknown; allowed: {', '.join(group_options(group))}")


def group_options(group: str) -> list[str]:
    """The options of ``group``: conf/, the searchpath's folders, the Python-configured ones."""
    names = set(PYTHON_OPTIONS.get(group, {}))
    for folder in (CONF_DIR, *search_dirs()):
        names |= {p.stem for p in (Path(folder) / group).glob("*.yaml")}
    return sorted(names)
