"""K learning runs of one table cell (the same configuration, K seeds), stepped together in one
process. A single run (``run.execute_run``) is a group of one.

Every run keeps its own environment, transfer strategy, random streams, evaluation tasks,
curve and result: its ``RunRecorder`` (recorder.py), which does all of a run's bookkeeping.
This loop only steps: per run, each tick does what a single run does, in the same order (act,
step the environment, the TD error if the strategy asks for it, observe, evaluate at the
evaluation points, end the episode and report it to the strategy). What the runs share is the
process and, with stacked learners, the network computations (lockstep/group.py). All runs take
one learning step per tick, so their updates, target copies and evaluation points fall on the
same ticks.

A run that diverges fails alone: its result is handed over at once and the others go on. An
exception in a callback (an interrupt) stops the group; results handed over before stay.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from functools import partial
from typing import TYPE_CHECKING

from ..learners.factory import make_learner, own_run_loop
from ..recorder import EvaluationFn, FinishFn, ProgressFn, RunRecorder, RunStreams
from ..results import RunResult
from .group import DEVICES, LearnerGroup, PerSeedLearners

if TYPE_CHECKING:
    from ..runspec import RunSpec

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


def check_group(specs: Sequence["RunSpec"]) -> None:
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
    if own_run_loop(first.algorithm, first.algorithm_target) is not None:
        raise ValueError(f"algorithm={first.algorithm} learns in its own loop (e.g. Stable-Baselines3's); "
                         "lockstep.runs must be 1 for it")


def cpu_group(specs: Sequence["RunSpec"], streams: Sequence[RunStreams]) -> PerSeedLearners:
    """Each run's own learner, as a single run has it."""
    spec = specs[0]
    return PerSeedLearners([
        make_learner(spec.algorithm, spec.representation, spec.algorithm_params,
                     spec.representation_params, world=spec.make_world(), seed=s.learner_seed,
                     algorithm_target=spec.algorithm_target,
                     representation_target_path=spec.representation_target)
        for s in streams])


def make_group(specs: Sequence["RunSpec"], streams: Sequence[RunStreams], device: str) -> LearnerGroup:
    """The learners of the group: per seed on the CPU, stacked networks on a GPU."""
    if device not in DEVICES:
        raise ValueError(f"lockstep.device={device!r} is unknown; allowed: {', '.join(DEVICES)}")
    spec = specs[0]
    if device == "cpu":
        return cpu_group(specs, streams)
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
    world = spec.make_world()  # its actions and sensor layout size the stacked networks
    return StackedDQN(config, [s.learner_seed for s in streams], num_actions=world.num_actions, device=device,
                      sensors=world.sensors)


def execute_lockstep(specs: Sequence["RunSpec"], hooks: Sequence[RunHooks] | None = None,
                     on_result: ResultFn | None = None, device: str = "cpu",
                     group: LearnerGroup | None = None) -> list[RunResult]:
    """Run the learning runs ``specs`` together; returns their results in order. ``on_result``
    receives each result as soon as its run ends (a diverged run ends early)."""
    for spec in specs:
        spec.validate()
    check_group(specs)
    streams = [RunStreams.of(spec) for spec in specs]
    return step_group(specs, streams, group if group is not None else make_group(specs, streams, device),
                      hooks, on_result, device)


def step_group(specs: Sequence["RunSpec"], streams: Sequence[RunStreams], group: LearnerGroup,
               hooks: Sequence[RunHooks] | None = None, on_result: ResultFn | None = None,
               device: str = "cpu") -> list[RunResult]:
    """The loop of execute_lockstep over a made ``group`` (execute_run: a CPU group of one, so
    that a single run's code digest does not take in the stacked networks it never uses)."""
    hooks = list(hooks) if hooks is not None else [RunHooks() for _ in specs]
    if len(hooks) != len(specs):
        raise ValueError(f"{len(specs)} runs but {len(hooks)} sets of callbacks")
    records = [RunRecorder(spec, stream, hook.progress, hook.progress_every, hook.on_evaluation)
               for spec, stream, hook in zip(specs, streams, hooks)]
    td_error = getattr(group, "td_error", None)
    if records[0].wants_td_error and td_error is None:  # the TD error must come before observe
        raise ValueError(f"strategy={specs[0].strategy} asks for the learner's TD errors, which "
                         f"{type(group).__name__} (lockstep.device={device}) does not compute; "
                         "use lockstep.device=cpu")
    envs = [spec.make_world().make_env("target") for spec in specs]
    observations: list = [None] * len(specs)
    results: list[RunResult | None] = [None] * len(specs)

    def finish(k: int) -> None:
        on_finish = hooks[k].on_finish
        results[k] = records[k].finish(group.learner(k, with_buffer=on_finish is not None), on_finish)
        if on_result is not None:
            on_result(k, results[k])

    active = list(range(len(specs)))
    while active:
        for k in active:
            if not records[k].in_episode:
                observations[k], _ = records[k].begin(envs[k])
        actions = group.act(active, [observations[k] for k in active], True)
        outcomes = []
        for k, action in zip(active, actions):
            obs = observations[k]
            next_obs, reward, terminated, truncated, _ = envs[k].step(action)
            # Before observe: the error the update learns from.
            td = td_error(k, obs, action, reward, next_obs, terminated) if records[k].wants_td_error else None
            group.observe(k, obs, action, reward, next_obs, terminated)
            observations[k] = next_obs
            outcomes.append((k, reward, terminated, truncated, td))
        group.learn()
        ended = []
        for k, reward, terminated, truncated, td in outcomes:
            record = records[k]
            record.step(reward, td)
            over = record.checkpoint(partial(group.learner, k))
            if terminated or truncated or over:
                group.end_episode(k)
                record.end_episode(terminated)
                if over:
                    ended.append(k)
        for k in ended:
            finish(k)
        active = [k for k in active if not records[k].over]
    return results  # type: ignore[return-value]
