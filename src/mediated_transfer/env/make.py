"""What ``gymnasium.make(ENV_ID, ...)`` builds (registered in env/__init__.py): the environment,
refusing at once, in one line, what Gymnasium would otherwise let fail late or ignore:

- ``render_mode="human"`` shows the rgb_array frames in a pygame window (Gymnasium's
  HumanRendering); without pygame that failed only at the first ``reset``, now at ``make``.
- ``max_episode_steps`` beyond the world's own limit (``-1``: none) was ignored silently: the
  world ends every episode after its ``config`` max_episode_steps (100) itself.

Nothing here is part of a run, which makes its environment directly.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Mapping

import gymnasium

from .config import WorldConfig
from .mediated_env import MediatedInteractionEnv


def make_env(scenario: str = "target", config: WorldConfig | Mapping | None = None,
             render_mode: str | None = None) -> gymnasium.Env:
    """The environment of ``gymnasium.make``: MediatedInteractionEnv, with a pygame window for
    ``render_mode="human"`` (refused here if pygame is missing)."""
    if render_mode != "human":
        return MediatedInteractionEnv(scenario, config, render_mode)
    if importlib.util.find_spec("pygame") is None:
        raise ValueError("render_mode='human' shows frames with pygame, which is not installed "
                         "(pip install pygame); render_mode='rgb_array' draws them without it")
    from gymnasium.wrappers import HumanRendering

    return HumanRendering(MediatedInteractionEnv(scenario, config, "rgb_array"))


# Gymnasium reads an entry point's render modes from its metadata: "human" is passed through to
# make_env (which adds the window), the others are as the environment's own.
make_env.metadata = {**MediatedInteractionEnv.metadata,  # type: ignore[attr-defined]
                     "render_modes": [*MediatedInteractionEnv.metadata["render_modes"], "human"]}


def check_episode_limit(env: gymnasium.Env) -> gymnasium.Env:
    """``env`` as ``gymnasium.make`` wrapped it, if its time limit is one the world keeps; a
    ValueError naming ``max_episode_steps`` otherwise (Gymnasium applies it as a wrapper)."""
    own = env.unwrapped.config.max_episode_steps
    limit = _time_limit(env)
    hint = "pass config={'max_episode_steps': k} (and max_episode_steps=k) for another limit"
    if limit is None:
        raise ValueError(f"max_episode_steps=-1 (no time limit) cannot hold: the world ends every episode "
                         f"after its config's max_episode_steps={own} steps; {hint}")
    if limit > own:
        raise ValueError(f"max_episode_steps={limit} exceeds the world's own limit, its config's "
                         f"max_episode_steps={own}, which would end episodes first; {hint}")
    return env


def _time_limit(env: gymnasium.Env) -> int | None:
    while isinstance(env, gymnasium.Wrapper):
        if isinstance(env, gymnasium.wrappers.TimeLimit):
            return env._max_episode_steps  # noqa: SLF001 - TimeLimit has no public accessor
        env = env.env
    return None
