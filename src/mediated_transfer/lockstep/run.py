"""K learning runs of one table cell (the same configuration, K seeds), stepped together in one
process: the lockstep counterpart of ``run.execute_run``.

Every run keeps its own environment, transfer strategy, random streams, evaluation tasks,
curve and result; per run, each step does what ``execute_run`` does, in the same order (act,
step the environment, observe, evaluate at the evaluation points, end the episode and report
it to the strategy). What the runs share is the process and, with stacked learners, the network
computations (lockstep/group.py). All runs take one learning step per tick, so their updates,
target copies and evaluation points fall on the same ticks.

A run that diverges fails alone: its result is handed over at once and the others go on. An
exception in a callback (an interrupt) stops the group; results handed over before stay.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

from ..env.mediated_env import MediatedInteractionEnv
from ..learners.factory import make_learner
from ..results import RunResult
from ..run import Curve, EvaluationFn, FinishFn, ProgressFn, RunSpec, RunStreams, own_run_loop, run_result
from ..transfer.strategy import EpisodeOutcome, start_episode, wants_td_error
from .group import DEVICES, LearnerGroup, PerSeedLearners

log = logging.getLogger("mediated_transfer")

ResultFn = Callable[[int, RunResult], None]
"""Called with (index of the run in the group, its result) as soon as a run ends."""


@dataclass
class RunHooks:
    """One run's callbacks, as ``execute_run`` takes them."""

    progress: ProgressFn | None = None
    progress_every: int = 0
    on_evaluation: EvaluationFn | None = None
    on_finish: FinishFn | None = None


@dataclass
class _Run:
    """The state of one run of the group between two steps."""

    spec: RunSpec
    streams: RunStreams
    hooks: RunHooks
    curve: Curve
    env: MediatedInteractionEnv
    env_seed: int | None
    step: int = 0
    observation: object = None
    task: object = None
    in_episode: bool = False
    episode_return: float = 0.0
    length: int = 0
    source_phase_end: int | None = None
    first_target_reward: int | None = None
    done: bool = False
    progress_every: int = field(default=0)


def check_group(specs: Sequence[RunSpec]) -> None:
    """ValueError unless ``specs`` are runs of one configuration with distinct seeds (what a
    lockstep group steps together: equal budgets and evaluation points, one network shape)."""
    if not specs:
        raise ValueError("a lockstep group needs at least one run")
    first = replace(specs[0], seed=0)
    for spec in specs[1:]:
        if replace(spec, seed=0) != first:
            raise ValueError(f"a lockstep group's runs must differ only in their seed: "
                             f"{specs[0].describe()} and {spec.describe()} differ otherwise")
    seeds = [s.seed for s in specs]
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"a lockstep group's seeds must be distinct, got {seeds}")
    if own_run_loop(first) is not None:
        raise ValueError(f"algorithm={first.algorithm} learns in its own loop (e.g. Stable-Baselines3's); "
                         "lockstep.runs must be 1 for it")


def make_group(specs: Sequence[RunSpec], streams: Sequence[RunStreams], device: str) -> LearnerGroup:
    """The learners of the group: per seed on the CPU, stacked networks on a GPU."""
    if device not in DEVICES:
        raise ValueError(f"lockstep.device={device!r} is unknown; allowed: {', '.join(DEVICES)}")
    spec = specs[0]
    if device == "cpu":
        return PerSeedLearners([
            make_learner(spec.algorithm, spec.representation, spec.algorithm_params,
                         spec.representation_params, world=spec.world, seed=s.learner_seed,
                         algorithm_target=spec.algorithm_target,
                         representation_target_path=spec.representation_target)
            for s in streams])
    if spec.algorithm != "dqn":
        raise ValueError(f"lockstep.device={device} stacks deep Q-networks; algorithm={spec.algorithm} "
                         "runs on the CPU (lockstep.device=cpu)")
    import torch

    from ..learners.factory import validate_learner_choice
    from .stacked import StackedDQN

    if device == "cuda" and not torch.cuda.is_available():  # before any work, in one line
        raise ValueError(f"lockstep.device=cuda: torch {torch.__version__} sees no CUDA device (built with "
                         f"CUDA {torch.version.cuda}); use lockstep.device=cpu, or a GPU node")

    config, _ = validate_learner_choice(spec.algorithm, spec.representation, spec.algorithm_params,
                                        spec.representation_params)
    return StackedDQN(config, [s.learner_seed for s in streams], device=device)


def execute_lockstep(specs: Sequence[RunSpec], hooks: Sequence[RunHooks] | None = None,
                     on_result: ResultFn | None = None, device: str = "cpu",
                     group: LearnerGroup | None = None) -> list[RunResult]:
    """Run the learning runs ``specs`` together; returns their results in order. ``on_result``
    receives each result as soon as its run ends (a diverged run ends early)."""
    for spec in specs:
        spec.validate()
    check_group(specs)
    hooks = list(hooks) if hooks is not None else [RunHooks() for _ in specs]
    if len(hooks) != len(specs):
        raise ValueError(f"{len(specs)} runs but {len(hooks)} sets of callbacks")
    streams = [RunStreams.of(spec) for spec in specs]
    if any(wants_td_error(s.strategy) for s in streams):
        raise ValueError(f"strategy={specs[0].strategy} asks for the learner's TD errors, which a lockstep "
                         "group does not compute: lockstep.runs must be 1 for it")
    if group is None:
        group = make_group(specs, streams, device)
    runs = []
    for spec, stream, hook in zip(specs, streams, hooks):
        curve = Curve(spec, stream, hook.on_evaluation)
        runs.append(_Run(spec, stream, hook, curve, MediatedInteractionEnv("target", spec.world),
                         stream.env_seed, progress_every=hook.progress_every or curve.every))
    results: list[RunResult | None] = [None] * len(runs)

    def finish(k: int) -> None:
        run = runs[k]
        run.done = True
        wall = run.curve.stop()
        learner = group.learner(k, with_buffer=run.hooks.on_finish is not None)
        if run.hooks.on_finish is not None:
            run.hooks.on_finish(learner)
        results[k] = run_result(run.spec, run.curve, run.streams.strategy, learner.stats,
                                run.source_phase_end, run.first_target_reward, wall)
        if on_result is not None:
            on_result(k, results[k])

    active = list(range(len(runs)))
    while active:
        for k in active:
            run = runs[k]
            if not run.in_episode:
                run.observation, _, run.task = start_episode(run.env, run.streams.strategy, run.env_seed)
                run.env_seed, run.in_episode = None, True
                run.episode_return, run.length = 0.0, 0
        actions = group.act(active, [runs[k].observation for k in active], True)
        outcomes = []
        for k, action in zip(active, actions):
            run = runs[k]
            next_obs, reward, terminated, truncated, _ = run.env.step(action)
            group.observe(k, run.observation, action, reward, next_obs, terminated)
            run.observation = next_obs
            outcomes.append((k, reward, terminated, truncated))
        group.learn()
        ended = []
        for k, reward, terminated, truncated in outcomes:
            run = runs[k]
            run.step += 1
            run.episode_return += reward
            run.length += 1
            step, spec = run.step, run.spec
            if reward > 0 and run.task is None and run.first_target_reward is None:
                run.first_target_reward = step
            if step % run.curve.every == 0:
                run.curve.evaluate(step, group.learner(k))
            if run.hooks.progress is not None and step % run.progress_every == 0:
                run.hooks.progress(step, spec.budget)
            if terminated or truncated or step >= spec.budget or run.curve.failure is not None:
                run.in_episode = False
                group.end_episode(k)
                strategy = run.streams.strategy
                was_done = strategy.done
                strategy.report(EpisodeOutcome(run.task, bool(terminated), run.episode_return, run.length, step))
                if not was_done and strategy.done:
                    run.source_phase_end = step
                if step >= spec.budget or run.curve.failure is not None:
                    ended.append(k)
        for k in ended:
            finish(k)
        active = [k for k in active if not runs[k].done]
    return results  # type: ignore[return-value]
