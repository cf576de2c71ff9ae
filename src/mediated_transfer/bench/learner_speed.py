"""Speed of the linear learners: time per learning step (act + observe) vs. one environment step.

In each of several short rounds, the environment takes a chunk of steps (uniformly random
actions, source and target tasks alternating, resets included; only ``env.step`` is timed) and
the recorded transitions are then fed to linear Q(lambda) with each representation: ``act``
(exploring) on the state, ``observe`` on the recorded transition, ``end_episode`` at episode
ends. The learners carry on from round to round. Medians over rounds are reported, so load
from other processes hits both sides of the ratio alike. Target: learner / env <= 1.

Random actions make long, truncated episodes, hence long eligibility traces: a pessimistic
setting for the learner.

Without the environment module, transitions are synthesised from random task sensor vectors
(random walks of the distances, random picks) and the ratio uses ``env_step_us``.
"""

from __future__ import annotations

import time

import numpy as np

from ..env import NUM_DISTANCES, OBSERVATION_SIZE, PICKING_LOCATIONS, WorldConfig, sample_task
from ..learners.fsr import FSRRepresentation
from ..learners.linear_q import LinearQConfig, LinearQLearner
from ..learners.rbf import RBFRepresentation

NUM_ACTIONS = 11
WARMUP_STEPS = 500


class _EnvRecorder:
    """Steps the environment with random actions, timing ``env.step`` only."""

    def __init__(self, seed: int):
        from ..env.mediated_env import MediatedInteractionEnv

        world = WorldConfig()
        self.envs = [MediatedInteractionEnv("source", world), MediatedInteractionEnv("target", world)]
        self.rng = np.random.default_rng(seed)
        self.envs[1].reset(seed=seed + 1)
        self.episode = 0
        self.obs, _ = self.envs[0].reset(seed=seed)

    def record(self, steps: int):
        """(transitions, seconds spent in env.step) for ``steps`` steps."""
        obs, nxt = np.empty((steps, OBSERVATION_SIZE)), np.empty((steps, OBSERVATION_SIZE))
        rewards, terms, ends = np.zeros(steps), np.zeros(steps, bool), np.zeros(steps, bool)
        actions = [int(a) for a in self.rng.integers(NUM_ACTIONS, size=steps)]
        env = self.envs[self.episode % 2]
        elapsed = 0.0
        for i, a in enumerate(actions):
            t0 = time.perf_counter()
            next_obs, r, terminated, truncated, _ = env.step(a)
            elapsed += time.perf_counter() - t0
            obs[i], nxt[i], rewards[i], terms[i] = self.obs, next_obs, r, terminated
            self.obs = next_obs
            if terminated or truncated:
                ends[i] = True
                self.episode += 1
                env = self.envs[self.episode % 2]
                self.obs, _ = env.reset()
        return (obs, nxt, actions, rewards, terms, ends), elapsed


def _synthesise(steps: int, seed: int, episode_length: int = 100):
    """Plausible transitions without the environment: distances random-walk from task starts."""
    world = WorldConfig()
    rng = np.random.default_rng(seed)
    obs = np.empty((steps + 1, OBSERVATION_SIZE))
    ends = np.zeros(steps + 1, dtype=bool)
    t = 0
    while t <= steps:
        s = sample_task("source" if rng.random() < 0.5 else "target", rng, world).sensor_vector(world)
        for _ in range(episode_length):
            if t > steps:
                break
            obs[t] = s
            s = s.copy()
            s[:NUM_DISTANCES] = np.abs(s[:NUM_DISTANCES] + rng.normal(0.0, 0.7, NUM_DISTANCES))
            if rng.random() < 0.2:  # a pick action changes the active location
                s[NUM_DISTANCES:] = 0.0
                s[NUM_DISTANCES + rng.integers(len(PICKING_LOCATIONS))] = 1.0
            t += 1
        ends[t - 1] = True
    actions = [int(a) for a in rng.integers(NUM_ACTIONS, size=steps)]
    return obs[:steps], obs[1:], actions, np.zeros(steps), np.zeros(steps, dtype=bool), ends[:steps]


def _chunk(data, start: int, stop: int):
    return tuple(part[start:stop] for part in data)


def _replay(learner: LinearQLearner, data) -> float:
    """Seconds spent in act + observe + end_episode over the transitions."""
    obs, nxt, actions, rewards, terms, ends = data
    act, observe, end = learner.act, learner.observe, learner.end_episode
    t0 = time.perf_counter()
    for i in range(len(actions)):
        o = obs[i]
        act(o, True)
        observe(o, actions[i], rewards[i], nxt[i], terms[i])
        if ends[i]:
            end()
    return time.perf_counter() - t0


def run(steps: int, env_step_us: float | None = None, seed: int = 0, rounds: int = 10) -> dict:
    """Measure microseconds per learning step for RBF and FSR and their ratios to an env step.

    ``env_step_us`` is only used when the environment module is not available.
    """
    if steps < rounds:
        raise ValueError(f"steps must be >= rounds ({rounds}), got {steps}")
    representations = [RBFRepresentation(), FSRRepresentation()]
    learners = {r.name: LinearQLearner(LinearQConfig(), r, NUM_ACTIONS, seed) for r in representations}
    # Warm-up on throwaway learners: numba compilation / cache loading is not a step cost.
    warmup = _synthesise(WARMUP_STEPS, seed)
    for r in representations:
        _replay(LinearQLearner(LinearQConfig(), r, NUM_ACTIONS, seed), warmup)
    try:
        recorder = _EnvRecorder(seed)
        source = "environment"
    except ImportError:
        recorder, source = None, "synthesised"
        synthetic = _synthesise(steps, seed)
    chunk = steps // rounds
    env_us, learner_us = [], {name: [] for name in learners}
    observations = []
    for k in range(rounds):
        if recorder is not None:
            data, env_seconds = recorder.record(chunk)
            env_us.append(env_seconds / chunk * 1e6)
        else:
            data = _chunk(synthetic, k * chunk, (k + 1) * chunk)
        observations.append(data[0][::10])
        for name, learner in learners.items():
            learner_us[name].append(_replay(learner, data) / chunk * 1e6)

    result: dict = {"steps": chunk * rounds, "transitions": source}
    result["env_step_us"] = float(np.median(env_us)) if env_us else env_step_us
    for name, times in learner_us.items():
        result[f"{name}_us_per_step"] = float(np.median(times))
        if env_us:
            ratio = float(np.median(np.array(times) / np.array(env_us)))
        else:
            ratio = result[f"{name}_us_per_step"] / env_step_us if env_step_us else None
        result[f"{name}_ratio_to_env"] = ratio
        result[f"{name}_rollbacks"] = learners[name].stats["rollbacks"]
    rbf = representations[0]
    sample = np.concatenate(observations)
    # Minus the one active binary entry: the Gaussians kept per state.
    result["rbf_mean_active_gaussians"] = float(np.mean([len(rbf.features(o)[0]) - 1 for o in sample]))
    _report(result)
    return result


def _report(r: dict) -> None:
    env = f"{r['env_step_us']:.1f} us" if r["env_step_us"] else "not measured"
    print(f"linear Q(lambda) over {r['steps']} {r['transitions']} transitions; env step: {env}")
    for name in ("rbf", "fsr"):
        ratio = r[f"{name}_ratio_to_env"]
        ratio_text = f"learner/env = {ratio:.2f} (target <= 1)" if ratio is not None else ""
        print(f"  {name}: {r[f'{name}_us_per_step']:.1f} us per learning step (act + observe)  {ratio_text}")
    print(f"  rbf: {r['rbf_mean_active_gaussians']:.1f} of 13824 Gaussians active per state on average")


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--env-step-us", type=float, default=None,
                        help="env step time to compare against when the env module is missing")
    args = parser.parse_args()
    run(args.steps, args.env_step_us)
