"""Environment speed: steps per second, and one step's cost against the physics it drives.

The ratio divides the time of environment steps (uniformly random actions, default config,
resets included) by the time spent inside the pymunk ``space.step`` calls those very steps made.
1.0 would mean the environment's Python costs nothing beyond pymunk; the aim is <= 2. Steps in
which nothing moves skip the physics: their cost counts and they add no physics, which raises
the ratio while raising throughput, so both are also given with that shortcut defeated.
Times are the CPU time of this thread (other processes on a shared machine distort them
little) and medians over rounds.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from ..env.mediated_env import NUM_ACTIONS, MediatedInteractionEnv


def _run_steps(env: MediatedInteractionEnv, actions: list[int]) -> float:
    step, reset = env.step, env.reset
    start = time.thread_time()
    for a in actions:
        _, _, terminated, truncated, _ = step(a)
        if terminated or truncated:
            reset()
    return time.thread_time() - start


def _instrument(env: MediatedInteractionEnv, skip_rest: bool) -> list[float]:
    """Time every physics call of ``env`` into the returned one-element accumulator."""
    world = env._world
    simulate, idle = world._simulate, world.idle
    physics_time = [0.0]

    def timed_simulate() -> None:
        start = time.thread_time()
        simulate()
        physics_time[0] += time.thread_time() - start

    def idle_always_simulating() -> None:
        world.at_rest = False
        idle()

    world._simulate = timed_simulate
    if not skip_rest:
        world.idle = idle_always_simulating
    return physics_time


def _measure(actions: list[int], scenario: str, rounds: int, seed: int, skip_rest: bool) -> dict:
    env = MediatedInteractionEnv(scenario)
    physics_time = _instrument(env, skip_rest)
    env.reset(seed=seed)
    _run_steps(env, actions[:500])  # warm-up
    chunk = len(actions) // rounds
    ratios, speeds, calls = [], [], 0
    for k in range(rounds):
        part = actions[k * chunk : (k + 1) * chunk]
        physics_time[0], physics_before = 0.0, env.physics_steps
        env_time = _run_steps(env, part)
        ratios.append(env_time / max(physics_time[0], 1e-12))
        speeds.append(len(part) / env_time)
        calls += env.physics_steps - physics_before
    return {
        "steps_per_second": float(np.median(speeds)),
        "ratio": float(np.median(ratios)),
        "physics_calls_per_step": calls / (chunk * rounds),
    }


def run(steps: int = 50_000, seed: int = 0, scenario: str = "target", rounds: int = 10) -> dict:
    """Measure, print a short report and return the numbers."""
    if steps < 10 * rounds:
        raise ValueError(f"steps must be >= {10 * rounds} (10 per round), got {steps}")
    rng = np.random.default_rng(seed)
    # Plain ints, as a learner passes them; drawn up front so the loop times only the env.
    actions = [int(a) for a in rng.integers(NUM_ACTIONS, size=steps)]
    used = _measure(actions, scenario, rounds, seed, skip_rest=True)
    busy = _measure(actions, scenario, rounds, seed, skip_rest=False)
    result = {
        "steps": steps,
        **used,
        "us_per_step": 1e6 / used["steps_per_second"],
        "steps_per_second_every_step_simulated": busy["steps_per_second"],
        "ratio_every_step_simulated": busy["ratio"],
    }
    print(
        f"environment ({scenario} tasks, random actions, {steps} steps, medians of {rounds} "
        f"rounds):\n"
        f"  {result['steps_per_second']:,.0f} steps/s ({result['us_per_step']:.1f} us/step), "
        f"{result['physics_calls_per_step']:.2f} space.step calls/step\n"
        f"  ratio env step / its space.step calls: {result['ratio']:.2f} (aim <= 2)\n"
        f"  every step simulated (no rest shortcut): "
        f"{result['steps_per_second_every_step_simulated']:,.0f} steps/s, "
        f"ratio {result['ratio_every_step_simulated']:.2f}"
    )
    return result


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="Environment speed benchmark.")
    parser.add_argument("--steps", type=int, default=50_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--scenario", default="target")
    args = parser.parse_args(argv)
    run(args.steps, args.seed, args.scenario)


if __name__ == "__main__":
    main()
