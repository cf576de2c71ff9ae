"""One learning run of one configuration: source tasks first, then the target task, evaluated.

This is the experiment of section V: a learner is seeded by solving the source tasks C that a
transfer strategy hands out (those episodes are learning steps too), then learns the target
task until the budget is spent. At evenly spaced points the greedy policy is evaluated on a
fixed set of target tasks; from that curve come the reward loss L_R and the time to threshold.

A single run is a lockstep group of one (lockstep/run.py): the one loop of the project's
learners, so a run computes the same alone or beside other seeds. What a run records, whichever
loop steps it (episodes, strategy calls, choices, evaluation, progress, divergence, the result),
is its RunRecorder's (recorder.py), also for learners with their own loop (run_sb3.py).
"""

from __future__ import annotations

from .learners.factory import own_run_loop as learner_run_loop
from .lockstep.run import RunHooks, cpu_group, step_group
from .recorder import EvaluationFn, FinishFn, ProgressFn, RunStreams
from .results import RunResult
from .runspec import MAX_SOURCE_POOL, MAX_STEPS, RunSpec  # noqa: F401 - where most callers import them


def execute_run(spec: RunSpec, progress: ProgressFn | None = None, progress_every: int = 0,
                on_evaluation: EvaluationFn | None = None,
                on_finish: FinishFn | None = None) -> RunResult:
    """Run one learning run and return its result (the caller writes it, with its code version).
    The callbacks see the run as it goes; they cannot change what it computes."""
    spec.validate()
    own_loop = own_run_loop(spec)
    if own_loop is not None:  # e.g. SB3 learns in its own loop (run_sb3.py)
        return own_loop(spec, progress, progress_every, on_evaluation, on_finish)
    # A group of one: the same calls in the same order as every run of a CPU group.
    streams = [RunStreams.of(spec)]
    hooks = RunHooks(progress, progress_every, on_evaluation, on_finish)
    return step_group([spec], streams, cpu_group([spec], streams), [hooks])[0]


def own_run_loop(spec: RunSpec):
    """The run loop ``spec``'s learner brings (its class's ``run_loop``), or None: the project's."""
    return learner_run_loop(spec.algorithm, spec.algorithm_target)
