"""What one learning run records, whichever loop steps its learner: written once here.

A loop (run.py's group of one, a lockstep group, SB3's own loop in run_sb3.py) only steps the
environment and the learner. Everything else about a run is its ``RunRecorder``'s: the seed's
streams (``RunStreams``), starting each episode as the strategy chooses, the episode's return,
length and TD errors, reporting the finished episode to the strategy with every signal it asks
for, the episode choices (transfer/choices.py), the evaluation points and divergence checks
(``Curve``), progress, the source phase's end, the first target-task reward, and the result.

The calls, in the order every loop makes them (docs/extending.md, "A learner with its own loop"):

    observation, info = recorder.begin(env)          # an episode starts (the strategy's task)
    ... the learner acts, env steps, the learner observes ...
    recorder.step(reward, td_error)                  # one learning step of that episode
    over = recorder.checkpoint(lambda: learner)      # evaluation point, progress; True: run over
    recorder.end_episode(terminated)                 # the episode ended (or the run did)
    result = recorder.finish(learner, on_finish)     # once, at the end

A loop that keeps several episodes in flight at once (SB3's vectorised environments, run_sb3.py
with ``algorithm.n_envs`` > 1) passes each environment's ``slot`` (0, 1, ...) to ``begin``,
``step`` and ``end_episode``: the run's one strategy still chooses every episode's task, in the
order the episodes begin, and hears each episode when it ends. Slot 0's environment is seeded
from the run's env stream as a single loop's is; slot k > 0's from its own stream of the seed.
A loop of one episode at a time leaves ``slot`` out (slot 0) and computes what it always has.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

import numpy as np

from . import metrics, plugins
from .learners.base import Learner
from .results import RESULTS_FORMAT, RunResult
from .transfer.choices import EpisodeChoices
from .transfer.source_tasks import source_task_set, task_sensors
from .transfer.strategy import EpisodeOutcome, Strategy, StrategyContext, solved_count, start_episode, wants_td_error

if TYPE_CHECKING:
    from .runspec import RunSpec

# Independent random streams of one run, all derived from its seed (never the seed itself:
# default_rng(seed) is also the source pool's stream when seed == source_set_seed).
_ENV_STREAM, _STRATEGY_STREAM, _EVAL_TASK_STREAM, _EVAL_NOISE_STREAM, _LEARNER_STREAM = 1, 2, 3, 4, 5

ProgressFn = Callable[[int, int], None]
EvaluationFn = Callable[[int, float, float], None]
"""Called at each evaluation point with (learning step, <R>, success rate)."""
FinishFn = Callable[[Learner], None]
"""Called with the trained learner at the end of the run (e.g. to save it)."""


def _stream_seed(seed: int, stream: int) -> int:
    return int(np.random.SeedSequence([seed, stream]).generate_state(1)[0])


def _slot_env_seed(seed: int, slot: int) -> int:
    """Seed of the first reset of the training environment in ``slot`` > 0 (several episodes in
    flight): a stream of the run's seed of its own, apart from every other."""
    return int(np.random.SeedSequence([seed, _ENV_STREAM, slot]).generate_state(1)[0])


def evaluate(learner: Learner, env, tasks, seed: int) -> tuple[float, float]:
    """<R> and success rate of the greedy policy on ``tasks``; the learner is left unchanged."""
    total, successes = 0.0, 0
    for i, task in enumerate(tasks):
        # Re-seeding at every evaluation point gives every point the same noise stream start.
        obs, _ = env.reset(seed=seed if i == 0 else None, options={"task": task})
        while True:
            obs, reward, terminated, truncated, _ = env.step(learner.act(obs, explore=False))
            total += reward
            if terminated or truncated:
                successes += bool(terminated)
                break
    return total / len(tasks), successes / len(tasks)


@dataclass
class RunStreams:
    """What a run draws from its seed, whichever loop drives its learner: each from its own
    stream, so that the strategy, the environment and the evaluation are the same for every
    learner of a seed."""

    learner_seed: int
    env_seed: int
    """Seed of the training environment's first reset (its target tasks and action noise)."""
    strategy: Strategy
    eval_tasks: list
    """The evaluation's target tasks: the same for every strategy and N_source of a seed."""
    eval_seed: int
    """Seed of the evaluation environment's action noise, at every evaluation point."""

    @classmethod
    def of(cls, spec: "RunSpec") -> "RunStreams":
        world = spec.make_world()
        context = StrategyContext(
            rng=np.random.default_rng(_stream_seed(spec.seed, _STRATEGY_STREAM)), world=spec.world,
            n_source=spec.n_source, task_space=world.task_space,
            task_sensors=functools.partial(task_sensors, world),
            build_source_tasks=lambda: source_task_set(spec.n_source, world, pool_size=spec.source_pool_size,
                                                       seed=spec.source_set_seed, cache_dir=spec.cache_dir))
        strategy = plugins.call(spec.strategy_class(), spec.strategy_params, context=context)
        eval_tasks = world.sample_tasks(
            "target", spec.eval_episodes, np.random.default_rng(_stream_seed(spec.seed, _EVAL_TASK_STREAM)))
        return cls(_stream_seed(spec.seed, _LEARNER_STREAM), _stream_seed(spec.seed, _ENV_STREAM),
                   strategy, eval_tasks, _stream_seed(spec.seed, _EVAL_NOISE_STREAM))


class Curve:
    """The run's evaluation points as it goes, the learning time between them (evaluation is
    not learning), and a divergence found at one of them."""

    def __init__(self, spec: "RunSpec", streams: RunStreams, on_evaluation: EvaluationFn | None = None):
        self.every = spec.budget // spec.eval_points
        self.env = spec.make_world().make_env("target")
        self.tasks, self.seed, self.on_evaluation = streams.eval_tasks, streams.eval_seed, on_evaluation
        self.steps: list[int] = []
        self.rewards: list[float] = []
        self.success: list[float] = []
        self.failure: str | None = None
        self.learn_time = 0.0
        self.started = self._mark = time.perf_counter()

    def evaluate(self, step: int, learner) -> None:
        """Evaluate ``learner``'s greedy policy at learning ``step``, then check it for divergence."""
        self.learn_time += time.perf_counter() - self._mark
        r, p = evaluate(learner, self.env, self.tasks, self.seed)
        self.steps.append(step)
        self.rewards.append(r)
        self.success.append(p)
        if self.on_evaluation is not None:
            self.on_evaluation(step, r, p)
        self.check(step, learner)
        self._mark = time.perf_counter()

    def check(self, step: int, learner) -> None:
        """Record a divergence of ``learner`` found at learning ``step`` as the run's failure."""
        reason = learner.divergence()
        if reason is not None:  # the rest of the budget would only repeat it
            self.failure = f"diverged by step {step}: {reason}"

    def stop(self) -> float:
        """End the learning time; returns the run's wall time so far."""
        now = time.perf_counter()
        self.learn_time += now - self._mark
        self._mark = now
        return now - self.started


class _Episode:
    """An episode in flight: its environment, its task (None: a target task the environment
    drew), the learning step it began at, its return, length and summed absolute TD error."""

    __slots__ = ("env", "task", "start", "ret", "length", "td")

    def __init__(self, env, task, start: int):
        self.env, self.task, self.start = env, task, start
        self.ret, self.length, self.td = 0.0, 0, 0.0


class RunRecorder:
    """One run's bookkeeping (module doc): a loop calls begin, step, checkpoint, end_episode and
    finish; it keeps no count, return, curve or strategy state of its own."""

    def __init__(self, spec: "RunSpec", streams: RunStreams | None = None, progress: ProgressFn | None = None,
                 progress_every: int = 0, on_evaluation: EvaluationFn | None = None,
                 check_before_evaluating: bool = False):
        """``check_before_evaluating``: check the learner for divergence before evaluating it at an
        evaluation point, and evaluate only a sound one (a diverged SB3 policy cannot act: its
        logits are not finite); otherwise the diverged point is evaluated and recorded, then
        the run fails (what the project's loop has always recorded)."""
        self.spec = spec
        self.streams = streams if streams is not None else RunStreams.of(spec)
        self.strategy = self.streams.strategy
        self.wants_td_error = wants_td_error(self.strategy)
        """The strategy asks for each episode's mean absolute TD error: the loop passes each
        transition's ``td_error`` (taken before the learner observes it) to ``step``."""
        self.curve = Curve(spec, self.streams, on_evaluation)
        self.choices = EpisodeChoices(self.curve.every, spec.eval_points,
                                      spec.make_world().task_space.target_distances[0])
        self.progress, self.progress_every = progress, progress_every or self.curve.every
        self.check_first = check_before_evaluating
        self.steps = 0
        """Learning steps of the run so far."""
        self.source_phase_end: int | None = None
        self.first_target_reward: int | None = None
        self._episodes: list[_Episode | None] = [None]
        """The episode in flight in each slot (module doc); None where none is."""
        self._seeded: set[int] = set()
        """Slots whose environment's first reset has been seeded."""

    @property
    def in_episode(self) -> bool:
        """An episode is in flight (in any slot)."""
        episodes = self._episodes
        return episodes[0] is not None if len(episodes) == 1 else any(e is not None for e in episodes)

    def in_flight(self, slot: int = 0) -> bool:
        """An episode is in flight in ``slot``."""
        return slot < len(self._episodes) and self._episodes[slot] is not None

    @property
    def over(self) -> bool:
        """The run has spent its budget, or failed."""
        return self.steps >= self.spec.budget or self.curve.failure is not None

    def begin(self, env, slot: int = 0) -> tuple:
        """Start an episode on ``env`` (a target-scenario environment of the run's world) in
        ``slot``: the strategy's next task, or a target task. Returns (observation, info)."""
        if slot in self._seeded:
            seed = None
        else:  # the first episode's reset of this slot's environment only
            seed = self.streams.env_seed if slot == 0 else _slot_env_seed(self.spec.seed, slot)
            self._seeded.add(slot)
        observation, info, task = start_episode(env, self.strategy, seed)
        while len(self._episodes) <= slot:
            self._episodes.append(None)
        self._episodes[slot] = _Episode(env, task, self.steps)
        return observation, info

    def step(self, reward: float, td_error: float | None = None, slot: int = 0) -> None:
        """One learning step of the episode in ``slot``, with its reward (and TD error, if asked for)."""
        self.steps += 1
        episode = self._episodes[slot]
        episode.ret += reward
        episode.length += 1
        if td_error is not None:
            episode.td += abs(td_error)
        if reward > 0 and episode.task is None and self.first_target_reward is None:
            self.first_target_reward = self.steps

    def checkpoint(self, learner: Callable[[], Learner]) -> bool:
        """After the learner has learned from the step: evaluate it at an evaluation point,
        report progress. ``learner`` is called only at an evaluation point (a stacked group
        builds a run's learner on demand). True: the run is over (budget spent, or diverged)."""
        step, curve = self.steps, self.curve
        if step % curve.every == 0:
            if self.check_first:
                curve.check(step, learner())
                if curve.failure is None:
                    curve.evaluate(step, learner())
            else:
                curve.evaluate(step, learner())
        if self.progress is not None and step % self.progress_every == 0:
            self.progress(step, self.spec.budget)
        return self.over

    def end_episode(self, solved: bool, slot: int = 0) -> None:
        """The episode in ``slot`` ended: in the goal (``solved``), at its step limit, or with
        the run. Records its choice and reports it to the strategy with every signal."""
        episode = self._episodes[slot]
        task = episode.task
        distance = (episode.env.unwrapped.task if task is None else task).target_distance
        self.choices.add(episode.start, task is None, distance, bool(solved))
        was_done = self.strategy.done
        self.strategy.report(EpisodeOutcome(task, bool(solved), episode.ret, episode.length, self.steps,
                                            episode.td / episode.length if self.wants_td_error else None))
        if not was_done and self.strategy.done:
            self.source_phase_end = self.steps
        self._episodes[slot] = None

    def finish(self, learner: Learner, on_finish: FinishFn | None = None) -> RunResult:
        """The run's result, once its loop has stopped (``on_finish`` sees the trained learner).
        An episode still open with steps in it ends with the run, unsolved (several: in slot order)."""
        for slot, episode in enumerate(self._episodes):
            if episode is not None and episode.length:
                self.end_episode(False, slot)
        wall = self.curve.stop()
        if on_finish is not None:
            on_finish(learner)
        return run_result(self.spec, self.curve, self.strategy, learner.stats, self.source_phase_end,
                          self.first_target_reward, wall, self.choices.summary())


def run_result(spec: "RunSpec", curve: Curve, strategy: Strategy, learner_stats: dict,
               source_phase_end: int | None, first_target_reward: int | None, wall: float,
               choices: dict | None = None) -> RunResult:
    """The RunResult of a finished (or failed) run. Its ``code`` is the job's to write (the job
    knows how the run was computed: alone or in a group)."""
    rewards_arr = np.asarray(curve.rewards)
    failure, world = curve.failure, spec.world
    # A failed run's partial curve has no reward loss or time to threshold: none is made up.
    return RunResult(
        algorithm=spec.algorithm,
        representation=spec.representation,
        strategy=spec.strategy,
        n_source=spec.n_source,
        seed=spec.seed,
        budget=spec.budget,
        steps=curve.steps,
        mean_reward=curve.rewards,
        success_rate=curve.success,
        reward_loss=math.nan if failure else metrics.reward_loss(rewards_arr, world.success_reward),
        time_to_threshold=None if failure else metrics.time_to_threshold(curve.steps, rewards_arr, spec.threshold),
        source_phase_end=source_phase_end,
        first_target_reward_step=first_target_reward,
        source_tasks_solved=solved_count(strategy),
        wall_time_s=wall,
        learning_steps_per_s=spec.budget / curve.learn_time if curve.learn_time > 0 else math.inf,
        learner_stats=dict(learner_stats),
        results_format=RESULTS_FORMAT,
        failure=failure,
        choices=choices,
    )
