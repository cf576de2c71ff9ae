"""One learning run of a Stable-Baselines3 learner (``algorithm=sb3_ppo``, ``sb3_dqn``): the
project's example of a learner with its own loop (docs/extending.md, "A learner with its own
loop").

The run is the project's: its ``RunRecorder`` (recorder.py) keeps everything a run records, as
for every learner. Only the loop is SB3's: ``model.learn`` on the training environment wrapped
in ``_RecordedEpisodes``, which starts each episode through the recorder (the strategy's task)
and hands it each step and each episode's end (so the strategy hears the episode before SB3's
automatic reset asks for the next task). A callback, called by SB3 after every learning step,
gives the recorder its checkpoint (evaluation points on the recorder's own environment, so the
training environment and every generator are untouched; progress) and stops learning at the
budget (PPO would otherwise finish its rollout) or at a divergence.

Several environments (``algorithm.n_envs`` = K > 1, PPO): what PPO users do to go faster. SB3's
``DummyVecEnv`` steps K training environments in this process (the table runs one run per core,
so subprocess environments would only oversubscribe the cores), and the policy acts for all K in
one forward pass; a rollout is ``n_steps`` x K learning steps. The run stays the project's:

- one strategy per run chooses every episode's task, in the order the episodes begin (each
  environment's reset asks it, environment 0 to K-1 within a step of the environments), and
  hears every episode, source or target, when it ends (``max_in_flight`` = K: the strategy
  accepts K episodes handed out and not yet reported);
- every environment's step is a learning step of the run (source episodes included): the
  recorder counts them one by one, so the evaluation points fall at the same learning steps as
  with K = 1 (a policy evaluated there has learned from every rollout finished before it, as
  with K = 1), and the budget stops the run at its exact step: the environments after it in that
  step of the environments do not step, and SB3 stops before it learns from that rollout;
- the environment in slot 0 is seeded from the run's env stream, slot k from its own stream of
  the seed (recorder.py), so a seed gives the same run.

What changes with K > 1, and why it is acceptable: the strategy chooses up to K - 1 episodes
before it hears the outcome of those in flight. So regular transfer (Algorithm 1) may hand out a
task that another environment is about to solve (it leaves C once), scaffolding (Algorithm 2)
chooses from C_solved as it stood when the episode began, and when C empties (the switch to the
target task, when the algorithm says) the episodes still in flight finish their source tasks
(at most K - 1 episodes, of at most the world's episode limit each) before every environment
learns the target task: ``source_phase_end`` is the step at which C emptied, as before. The
strategy's decisions are its own (the algorithms' rules are unchanged); only their information
lags by the episodes in flight, as in any vectorised or distributed curriculum.
With K = 1 the run computes exactly what it computed before the key existed.
"""

from __future__ import annotations

import functools

import gymnasium
import numpy as np
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import DummyVecEnv

from .learners.factory import make_features
from .learners.sb3 import SB3Learner
from .recorder import EvaluationFn, FinishFn, ProgressFn, RunRecorder
from .results import RunResult


def execute_sb3_run(spec, progress: ProgressFn | None = None, progress_every: int = 0,
                    on_evaluation: EvaluationFn | None = None,
                    on_finish: FinishFn | None = None) -> RunResult:
    """run.execute_run for an SB3 learner (it calls this one; ``spec`` is validated)."""
    # A diverged SB3 policy cannot act (non-finite logits): check before evaluating.
    record = RunRecorder(spec, None, progress, progress_every, on_evaluation, check_before_evaluating=True)
    world = spec.make_world()
    n_envs = int(spec.algorithm_params.get("n_envs", 1))
    if n_envs == 1:
        env = DummyVecEnv([lambda: _RecordedEpisodes(world.make_env("target"), record)])
    else:
        record.strategy.max_in_flight = n_envs  # RunSpec.validate: the strategy accepts it
        slots = [_RecordedSlot(world.make_env("target"), record, k) for k in range(n_envs)]
        env = DummyVecEnv([functools.partial(_the, slot) for slot in slots])
    features = make_features(spec.representation, spec.representation_params, spec.representation_target,
                             world.sensors)
    learner = SB3Learner.of(spec.algorithm, spec.algorithm_params, features, world,
                            record.streams.learner_seed, env=env, num_actions=world.num_actions)
    if n_envs == 1:
        callback: BaseCallback = _RunCallback(record, learner)
    else:
        for slot in slots:
            slot.learner = learner
        callback = _SlotsCallback(record, learner)
    try:
        learner.model.learn(total_timesteps=spec.budget, callback=callback)
    except ValueError:
        # A diverged PPO policy fails in torch.distributions (non-finite logits) mid-rollout.
        reason = learner.divergence()
        if reason is None:
            raise
        record.curve.failure = f"diverged by step {learner.model.num_timesteps}: {reason}"
    return record.finish(learner, on_finish)


class _RecordedEpisodes(gymnasium.Wrapper):
    """The training environment as the recorder runs its episodes (what TransferWrapper does for
    any Gymnasium learner, here through the run's recorder)."""

    def __init__(self, env: gymnasium.Env, record: RunRecorder):
        super().__init__(env)
        self.record = record

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        # SB3 seeds the first reset with the learner's seed: the recorder seeds it from the run's
        # env stream instead, as for every learner (the same target tasks and action noise).
        if self.record.in_episode:  # SB3 reset before the episode ended: not solved
            self.record.end_episode(False)
        return self.record.begin(self.env)

    def step(self, action):
        observation, reward, terminated, truncated, info = self.env.step(action)
        self.record.step(float(reward))
        if terminated or truncated:
            self.record.end_episode(bool(terminated))
        return observation, reward, terminated, truncated, info


class _RunCallback(BaseCallback):
    """Called by SB3 after every learning step (its ``num_timesteps`` is the recorder's step count)."""

    def __init__(self, record: RunRecorder, learner: SB3Learner):
        super().__init__(verbose=0)
        self.record, self.learner = record, learner

    def _on_step(self) -> bool:
        if self.locals["dones"][0]:
            self.learner.episodes += 1
        return not self.record.checkpoint(lambda: self.learner)


def _the(env: gymnasium.Env) -> gymnasium.Env:
    return env


class _RecordedSlot(gymnasium.Wrapper):
    """Training environment ``slot`` of K (``algorithm.n_envs`` > 1) as the recorder runs its
    episodes: each step is a learning step of the run, checkpointed at once (the evaluation
    points and the budget fall on exact learning steps, not on steps of all K environments)."""

    def __init__(self, env: gymnasium.Env, record: RunRecorder, slot: int):
        super().__init__(env)
        self.record, self.slot = record, slot
        self.learner: SB3Learner | None = None
        """Set once the learner is built (it needs this environment's spaces)."""
        self._observation = None

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        # Seeds from SB3 are ignored: the recorder seeds each slot's first reset (module doc).
        if self.record.in_flight(self.slot):  # SB3 reset before the episode ended: not solved
            self.record.end_episode(False, self.slot)
        self._observation, info = self.record.begin(self.env, self.slot)
        return self._observation, info

    def step(self, action):
        record = self.record
        if record.over:
            # The budget was spent (or the run failed) by an earlier environment of this step of
            # the environments: this one does not step, and SB3 stops before learning from it.
            return self._observation, 0.0, False, False, {}
        observation, reward, terminated, truncated, info = self.env.step(action)
        self._observation = observation
        record.step(float(reward), slot=self.slot)
        if terminated or truncated:
            record.end_episode(bool(terminated), self.slot)
        record.checkpoint(lambda: self.learner)
        return observation, reward, terminated, truncated, info


class _SlotsCallback(BaseCallback):
    """Called by SB3 after every step of the K environments: counts the episodes that ended and
    stops learning once the run is over (the environments checkpoint each learning step)."""

    def __init__(self, record: RunRecorder, learner: SB3Learner):
        super().__init__(verbose=0)
        self.record, self.learner = record, learner

    def _on_step(self) -> bool:
        self.learner.episodes += int(np.count_nonzero(self.locals["dones"]))
        if self.record.over:
            # SB3 counted K steps for the last step of the environments; the run took fewer.
            self.model.num_timesteps = self.record.steps
            return False
        return True
