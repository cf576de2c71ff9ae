"""Environment speed: steps per second, and the Python a step adds to the C physics it drives.

Two workloads are recorded as episodes (noise seed, task, actions) and replayed through fresh
environments, timing only ``reset`` and ``step``:

* learner trajectories, the aim's workload: linear Q(lambda) + RBF with its tuned values learns
  under regular transfer (N_source = 50, the run loop of run.py without evaluations) for
  ``LEARN_STEPS`` steps. A learner picks, pushes and drags objects, the physics a run pays
  for; random actions rarely touch one.
* uniformly random actions on target tasks (the second line).

Every replay runs the whole recorded sequence in order (an episode's contacts can depend on
the episodes before it) and times about ``steps`` steps of episodes spread evenly over it.

The figure is the overhead: (env step time - time inside ``cpSpaceStep``) / time inside
``cpSpaceStep``; aim <= 1, i.e. a step costs at most twice the Chipmunk physics it drives.
The env time comes from a plain environment. The physics time comes from a twin replaying the
same episodes (so the very same states and calls), whose substep loop is timed as one block per
step with ``time.perf_counter``; from each block the median cost of the same block around a
trivial Chipmunk call (timer, loop and cffi call) is subtracted, leaving time inside Chipmunk.
Rounds alternate plain and twin on the same episodes and report medians, so load from other
processes hits both sides alike. Steps that move nothing skip the physics: they cost Python and
add no physics.
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import dataclass

import numpy as np
from pymunk._chipmunk_cffi import lib as _cp

from ..env.mediated_env import NUM_ACTIONS, MediatedInteractionEnv
from ..env.task import Task, sample_task

LEARN_STEPS = 100_000
"""Learning steps whose episodes the learner workload draws from."""
N_SOURCE = 50
LEARNER_OVERRIDES = ("algorithm=linear_q", "representation=rbf", "strategy=regular",
                     f"n_source={N_SOURCE}")
WARMUP_EPISODES = 1  # untimed: first calls fill caches


@dataclass(frozen=True)
class Episode:
    """One episode, replayable bit for bit: the action noise comes from ``noise_seed``."""

    noise_seed: int
    task: Task
    actions: tuple[int, ...]
    final_observation: np.ndarray


def _start(env: MediatedInteractionEnv, noise_seed: int, task: Task):
    # A noise generator per episode (run.py has one per run) and the task given, not drawn
    # from it: a replay needs only the episode's record.
    env.np_random = np.random.default_rng(noise_seed)
    return env.reset(options={"task": task})[0]


def learner_episodes(learn_steps: int = LEARN_STEPS, seed: int = 0) -> list[Episode]:
    """The episodes of a learning run of linear Q(lambda) + RBF (tuned) with regular transfer."""
    from ..config.compose import compose_config
    from ..config.spec import run_spec
    from ..learners.factory import make_learner
    from ..transfer.source_tasks import sensor_vectors, source_task_set
    from ..transfer.strategy import EpisodeOutcome, make_strategy

    spec = run_spec(compose_config([*LEARNER_OVERRIDES, f"seed={seed}"]))
    world = spec.world
    learner = make_learner(spec.algorithm, spec.representation, spec.algorithm_params,
                           spec.representation_params, world=world, seed=seed)
    tasks = source_task_set(spec.n_source, world, pool_size=spec.source_pool_size,
                            seed=spec.source_set_seed)
    strategy = make_strategy(spec.strategy, tasks, sensor_vectors(tasks, world),
                             np.random.default_rng(seed))
    env = MediatedInteractionEnv("target", world)
    target_tasks = np.random.default_rng([seed, 1])
    episodes: list[Episode] = []
    steps = 0
    while steps < learn_steps:
        task = None if strategy.done else strategy.next_task()
        source = task is not None
        if not source:
            task = sample_task("target", target_tasks, world)
        noise_seed = seed * 1_000_003 + len(episodes)
        obs = _start(env, noise_seed, task)
        actions = []
        terminated = truncated = False
        while not (terminated or truncated):
            action = learner.act(obs, explore=True)
            next_obs, reward, terminated, truncated, _ = env.step(action)
            learner.observe(obs, action, reward, next_obs, terminated)
            actions.append(action)
            obs = next_obs
        learner.end_episode()
        strategy.report(EpisodeOutcome(task if source else None, bool(terminated), 0.0, len(actions), steps))
        steps += len(actions)
        episodes.append(Episode(noise_seed, task, tuple(actions), obs))
    return episodes


def random_episodes(steps: int, seed: int = 0) -> list[Episode]:
    """Target-task episodes of uniformly random actions, ``steps`` steps or a few more."""
    env = MediatedInteractionEnv("target")
    rng = np.random.default_rng(seed)
    episodes: list[Episode] = []
    total = 0
    while total < steps:
        noise_seed = seed * 1_000_003 + len(episodes)
        obs = _start(env, noise_seed, sample_task("target", rng, env.config))
        actions = []
        terminated = truncated = False
        while not (terminated or truncated):
            actions.append(int(rng.integers(NUM_ACTIONS)))  # plain ints, as a learner passes
            obs, _, terminated, truncated, _ = env.step(actions[-1])
        total += len(actions)
        episodes.append(Episode(noise_seed, env.task, tuple(actions), obs))
    return episodes


def _play(env: MediatedInteractionEnv, episodes: list[Episode], timed: list[bool],
          physics: list[float] | None = None) -> tuple[float, int, int]:
    """Replay ``episodes`` in order; (seconds in reset and step, steps, physics substeps) of
    the ``timed`` ones. Untimed ones are replayed too: an episode's contacts can depend on the
    episodes before it (Chipmunk keeps state across resets), so only the full sequence replays
    the recording bit for bit. ``physics``: the twin's accumulator, kept to timed episodes."""
    generators = [np.random.default_rng(e.noise_seed) for e in episodes]  # made untimed
    reset, step, clock = env.reset, env.step, time.perf_counter
    elapsed, steps, substeps = 0.0, 0, 0
    for episode, generator, timing in zip(episodes, generators, timed):
        env.np_random = generator
        physics_before, substeps_before = physics and physics[0], env.physics_steps
        start = clock()
        reset(options={"task": episode.task})
        for a in episode.actions:
            out = step(a)
        stop = clock()
        if timing:
            elapsed += stop - start
            steps += len(episode.actions)
            substeps += env.physics_steps - substeps_before
        elif physics:
            physics[0] = physics_before
        if not ((out[2] or out[3]) and np.array_equal(out[0], episode.final_observation)):
            raise RuntimeError("a replayed episode diverged from its recording")
    return elapsed, steps, substeps


def _timed_twin() -> tuple[MediatedInteractionEnv, list[float]]:
    """An environment whose physics substeps are timed, as a block per step, into the
    returned accumulator (seconds inside ``cpSpaceStep``)."""
    env = MediatedInteractionEnv("target")
    world = env._world
    space, dt, n = world._space_cp, world._dt, world._substeps
    step, clock = _cp.cpSpaceStep, time.perf_counter
    # The same block around a trivial Chipmunk call: timer, loop and cffi calls, not physics
    # (setting the damping the space already has changes nothing).
    set_damping, damping = _cp.cpSpaceSetDamping, world.space.damping
    empty = []
    for _ in range(20_000):
        start = clock()
        for _ in range(n):
            set_damping(space, damping)
        empty.append(clock() - start)
    empty_cost = statistics.median(empty)
    physics = [0.0]

    def timed_simulate() -> None:
        start = clock()
        for _ in range(n):
            step(space, dt)
        physics[0] += clock() - start - empty_cost
        world.physics_steps += n

    world._simulate = timed_simulate
    return env, physics


def measure(episodes: list[Episode], steps: int, rounds: int) -> dict:
    """Medians over rounds of steps/s and overhead on about ``steps`` steps of ``episodes``,
    taken evenly from the whole list after a warm-up; substeps per step over all of them."""
    total = sum(len(e.actions) for e in episodes[WARMUP_EPISODES:])
    stride = max(1, total // steps)
    timed = [i >= WARMUP_EPISODES and (i - WARMUP_EPISODES) % stride == 0
             for i in range(len(episodes))]
    plain = MediatedInteractionEnv("target")
    twin, physics = _timed_twin()
    bounds = np.linspace(0, len(episodes), rounds + 1).astype(int)
    speeds, overheads, steps_done, substeps = [], [], 0, 0
    for k in range(rounds):
        part, flags = episodes[bounds[k] : bounds[k + 1]], timed[bounds[k] : bounds[k + 1]]
        physics[0] = 0.0
        if k % 2:  # alternate which goes first
            env_time, n, calls = _play(plain, part, flags)
            _play(twin, part, flags, physics)
        else:
            _play(twin, part, flags, physics)
            env_time, n, calls = _play(plain, part, flags)
        if n:
            speeds.append(n / env_time)
            overheads.append((env_time - physics[0]) / physics[0])
        steps_done += n
        substeps += calls
    return {
        "steps": steps_done,
        "steps_per_second": statistics.median(speeds),
        "overhead": statistics.median(overheads),
        "physics_calls_per_step": substeps / steps_done,
    }


def run(steps: int = 20_000, seed: int = 0, rounds: int = 10,
        learn_steps: int = LEARN_STEPS) -> dict:
    """Measure both workloads, print a short report and return the numbers."""
    if steps < 100 * rounds:
        raise ValueError(f"steps must be >= {100 * rounds} (an episode per round), got {steps}")
    learner = measure(learner_episodes(max(learn_steps, steps), seed), steps, rounds)
    rand = measure(random_episodes(steps + 100, seed), steps, rounds)  # + the warm-up
    result = {**learner, "us_per_step": 1e6 / learner["steps_per_second"],
              "learn_steps": learn_steps, **{f"random_{k}": v for k, v in rand.items()}}
    print(f"environment, medians of {rounds} rounds; overhead = (env step - time in cpSpaceStep) "
          f"/ time in cpSpaceStep (aim <= 1):")
    for name, r in (("learner trajectories", learner), ("random actions", rand)):
        print(f"  {name:20s} {r['steps_per_second']:9,.0f} steps/s  "
              f"{r['physics_calls_per_step']:5.2f} substeps/step  overhead {r['overhead']:.2f}  "
              f"({r['steps']} steps)")
    return result


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="Environment speed benchmark.")
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--learn-steps", type=int, default=LEARN_STEPS)
    args = parser.parse_args(argv)
    run(args.steps, args.seed, learn_steps=args.learn_steps)


if __name__ == "__main__":
    main()
