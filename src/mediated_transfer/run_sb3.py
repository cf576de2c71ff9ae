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
"""

from __future__ import annotations

import gymnasium
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
    env = DummyVecEnv([lambda: _RecordedEpisodes(world.make_env("target"), record)])
    features = make_features(spec.representation, spec.representation_params, spec.representation_target,
                             world.sensors)
    learner = SB3Learner.of(spec.algorithm, spec.algorithm_params, features, world,
                            record.streams.learner_seed, env=env, num_actions=world.num_actions)
    try:
        learner.model.learn(total_timesteps=spec.budget, callback=_RunCallback(record, learner))
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
