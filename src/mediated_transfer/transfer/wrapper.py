"""The transfer strategies as a Gymnasium wrapper, for any learner that learns on a Gymnasium env.

``TransferWrapper(env, strategy)`` makes every ``reset`` start the episode the strategy chooses
(Algorithm 1 or 2: a source task of C, or once C is empty a target task), and tells the strategy
at the episode's end whether it solved its source task. It drives the strategy exactly as the
project's own loop does (``start_episode`` / ``report_episode`` in strategies.py, shared by
both): with the same strategy, seed and actions, it starts the same tasks in the same order.

``env`` is an environment of a world (env/door.py) of scenario "target", bare or wrapped:
``world.make_env("target")``, or for the paper's world a ``MediatedInteractionEnv`` (e.g.
``gymnasium.make(ENV_ID)``). What the wrapper relies on is the world's contract: a plain reset
samples a target task from the environment's seeded generator, ``reset(options={"task": t})``
starts a task of the world's task space (the strategy's tasks), and the observation is the
world's sensor vector with one of its actions per step. ``world`` (default: the paper's) is
checked against ``env``: its sensor vector's size and its number of actions.

Info: every ``reset`` and ``step`` adds ``source_phase`` (this episode learns a source task) and
``solved_count`` (source tasks solved so far, |C_solved|).

What it does not support, and refuses in one line:
- a strategy used in another process than the one that made it (a subprocess vector env:
  gymnasium's AsyncVectorEnv, SB3's SubprocVecEnv): each worker would hold its own copy of C and
  run a curriculum of its own. Use gymnasium.vector.SyncVectorEnv or SB3's DummyVecEnv.
- one strategy shared by episodes that run at the same time (several sub-environments of a
  vector env): Algorithms 1 and 2 hand out one source task at a time. Give each sub-environment
  its own strategy (each then has its own C), or use one environment.
- reset options: the strategy chooses every task.
A strategy made inside each worker of a subprocess vector env cannot be told from a legitimate
one: each worker then silently runs its own curriculum over its own copy of C.

A reset before the episode ended (e.g. a learner's time limit shorter than the env's) reports
the pending source task as not solved, as the project's loop does when its budget ends mid-
episode.
"""

from __future__ import annotations

import os
import weakref
from collections.abc import Mapping

import gymnasium

from .strategy import EpisodeOutcome, Strategy, solved_count, start_episode

# Which wrapper has a source episode open on a strategy (weak both ways: neither is kept alive).
_OPEN_EPISODES: "weakref.WeakKeyDictionary[Strategy, weakref.ref]" = weakref.WeakKeyDictionary()


class TransferWrapper(gymnasium.Wrapper):
    """Episodes chosen by a transfer strategy (``strategy=none``, ``regular`` or ``scaffolded``)."""

    def __init__(self, env: gymnasium.Env, strategy: Strategy, world=None):
        super().__init__(env)
        if world is None:
            from ..env.paper import PaperWorld

            world = PaperWorld()
        _check_env(env, world)
        # A world's environment without a scenario attribute is the target scenario by contract
        # (world.make_env("target")); one that names another cannot start target tasks.
        scenario = getattr(env.unwrapped, "scenario", "target")
        if scenario != "target":
            raise ValueError(f"TransferWrapper needs an environment of scenario 'target' (its reset "
                             f"samples the target tasks), got scenario {scenario!r}")
        self.world = world
        if not isinstance(strategy, Strategy):
            raise ValueError(f"strategy must be a transfer strategy (transfer/strategy.py: next_task, "
                             f"report, done), got {type(strategy).__name__}")
        self.strategy = strategy
        self._task = None
        self._open = False
        self._return, self._length, self._steps = 0.0, 0, 0

    @property
    def source_phase(self) -> bool:
        """True while the current episode learns a source task."""
        return self._task is not None

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        if options is not None and not (isinstance(options, Mapping) and not options):
            raise ValueError(f"TransferWrapper.reset takes no options (the strategy chooses every "
                             f"task), got {options!r}")
        _check_process(self.strategy)
        if self._open:  # reset before the episode ended: its source task was not solved
            self._close(solved=False)
        holder = _OPEN_EPISODES.get(self.strategy)
        if holder is not None and holder() is not None:
            raise RuntimeError("TransferWrapper: this strategy has a source episode open in another "
                               "environment; Algorithms 1 and 2 hand out one task at a time: give each "
                               "(sub-)environment its own strategy, or use one environment")
        observation, info, self._task = start_episode(self.env, self.strategy, seed)
        self._open = True
        self._return, self._length = 0.0, 0
        if self._task is not None:
            _OPEN_EPISODES[self.strategy] = weakref.ref(self)
        return observation, self._info(info)

    def step(self, action):
        if not self._open:
            raise RuntimeError("TransferWrapper: the episode is over (or never started): call reset() first")
        observation, reward, terminated, truncated, info = self.env.step(action)
        self._return += float(reward)
        self._length += 1
        self._steps += 1
        source_phase = self.source_phase
        if terminated or truncated:
            self._close(solved=bool(terminated))
        info = self._info(info)
        info["source_phase"] = source_phase  # of the episode this step belongs to
        return observation, reward, terminated, truncated, info

    def _close(self, solved: bool) -> None:
        self.strategy.report(EpisodeOutcome(self._task, solved, self._return, self._length, self._steps))
        if self._task is not None:
            _OPEN_EPISODES.pop(self.strategy, None)
        self._task, self._open = None, False

    def _info(self, info: dict) -> dict:
        info = dict(info)
        info["source_phase"] = self.source_phase
        info["solved_count"] = solved_count(self.strategy)
        return info


def _check_env(env: gymnasium.Env, world) -> None:
    """ValueError (one line) unless ``env`` looks like an environment of ``world``: an
    observation of its sensor vector's size and its number of discrete actions."""
    observation, actions = env.observation_space, env.action_space
    shape = getattr(observation, "shape", None)
    n = getattr(actions, "n", None)
    size, num_actions = world.sensors.size, world.num_actions
    if shape != (size,) or n != num_actions:
        raise ValueError(f"TransferWrapper wraps an environment of the world {type(world).__name__} "
                         f"(observations of {size} sensors, {num_actions} actions; pass world= for "
                         f"another world), got {type(env.unwrapped).__name__} with observation shape "
                         f"{shape} and {n if n is not None else type(actions).__name__} actions")


def _check_process(strategy: Strategy) -> None:
    owner = getattr(strategy, "owner_pid", None)  # None: a strategy without C (none)
    if owner is not None and owner != os.getpid():
        raise RuntimeError(
            f"TransferWrapper: the strategy (its source task set C) was made in process {owner} and "
            f"is used in process {os.getpid()}: a subprocess vector env (gymnasium AsyncVectorEnv, "
            "SB3 SubprocVecEnv) would give each worker its own copy of C; use "
            "gymnasium.vector.SyncVectorEnv or SB3's DummyVecEnv")
