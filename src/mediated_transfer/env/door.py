"""The world door: the one place that builds a run's world from its ``env`` option.

An ``env`` option's ``_target_`` names a world class by dotted path, as a strategy's or a
learner's does (plugins.py); its other keys are the fields of that class's ``config_class``.
The paper's world (env/paper.py) comes through the same door as a user's (docs/extending.md,
"A world of one's own"). A world class provides:

- ``config_class``: a frozen dataclass of its keys (defaults for keys an option leaves out);
  it has ``success_reward`` and ``max_episode_steps`` (a subclass of WorldConfig has them all);
- ``__init__(config)``; then ``config``, ``sensors`` (env/sensors.py), ``num_actions``,
  ``action_names``, ``task_space`` (env/task_space.py's interface);
- ``make_env(scenario, render_mode=None)``: a Gymnasium environment whose ``reset(options=
  {"task": task})`` starts a task of its task space; ``sample_tasks(scenario, n, rng)``;
  ``check_room(scenario)``; optionally ``scripted_policy(env, seed)``.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Mapping
from typing import Any

from .. import plugins
from ..mapping import config_from_mapping

PAPER_WORLD = "mediated_transfer.env.paper.PaperWorld"
"""The ``_target_`` of ``env=default`` and of results recorded before worlds had one."""
WORLD_METHODS = ("make_env", "sample_tasks", "check_room", "sensors", "num_actions", "task_space")
"""What the project calls on a world (the interface check names the first one missing)."""


def world_class(target: str | None) -> type:
    """The world class ``target`` names (None: the paper's); ValueError in one line if it is
    not importable, not a class, or lacks a part of the world interface."""
    path = target or PAPER_WORLD
    cls = plugins.locate("env", path)
    if not isinstance(cls, type):
        raise ValueError(f"env._target_={path}: not a class (a world is a class with a config_class)")
    plugins.check_interface("env", cls, WORLD_METHODS, "world")
    config_class = getattr(cls, "config_class", None)
    if not (isinstance(config_class, type) and dataclasses.is_dataclass(config_class)):
        raise ValueError(f"env._target_={path}: {cls.__name__}.config_class must be a dataclass of its env keys")
    return cls


def world_config(target: str | None, values: Any):
    """The config of the world ``target`` names from its option's keys (a mapping without
    ``_target_``), or ``values`` itself if it is already one; an unknown key is refused in one
    line naming the allowed ones."""
    config_class = world_class(target).config_class
    if isinstance(values, config_class):
        return values
    if not isinstance(values, Mapping):
        raise ValueError(f"env must be a mapping of {config_class.__name__}'s keys, got {type(values).__name__}")
    return config_from_mapping(config_class, values, "env")


def split_option(node: Mapping[str, Any]) -> tuple[str | None, dict[str, Any]]:
    """(``_target_``, the world's keys) of an ``env`` node as Hydra composed it."""
    values = dict(node)
    return values.pop(plugins.TARGET, None), values


def as_world(world):
    """The world ``world`` describes: itself when it is one (it has a task space), the paper's
    world of it when it is a config (a WorldConfig), the paper's default world for None."""
    if hasattr(world, "task_space"):
        return world
    return build_world(None, world if world is not None else world_class(None).config_class())


@functools.lru_cache(maxsize=64)
def build_world(target: str | None, config):
    """The world of a run: ``world_class(target)(config)``; the same object for the same
    (target, config), since a world only describes (its environments are made fresh)."""
    return world_class(target)(world_config(target, config))

