"""One learning run of a Stable-Baselines3 learner (``algorithm=sb3_ppo``, ``sb3_dqn``).

The run is the project's (run.py): the same seed streams, strategy and evaluation tasks
(``RunStreams``), the same evaluation points and greedy evaluation with action noise (``Curve``),
the same result (``run_result``). Only the loop is SB3's: ``model.learn`` on the training
environment wrapped in ``TransferWrapper``, which starts each episode as the strategy chooses,
exactly as run.py's loop does. A callback, called by SB3 after every learning step, evaluates
the policy at the evaluation points (on its own environment, so the training environment and
every generator are untouched), notes the source phase's end and the first target-task reward,
and stops learning at the budget (PPO would otherwise finish its rollout) or at a divergence.
"""

from __future__ import annotations

from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import DummyVecEnv

from .env.mediated_env import MediatedInteractionEnv
from .learners.factory import make_features
from .learners.sb3 import SB3Learner
from .results import RunResult
from .run import Curve, EvaluationFn, FinishFn, ProgressFn, RunSpec, RunStreams, run_result
from .transfer.wrapper import TransferWrapper


def execute_sb3_run(spec: RunSpec, progress: ProgressFn | None = None, progress_every: int = 0,
                    on_evaluation: EvaluationFn | None = None,
                    on_finish: FinishFn | None = None) -> RunResult:
    """run.execute_run for an SB3 learner (it calls this one; ``spec`` is validated)."""
    streams = RunStreams.of(spec)
    strategy = streams.strategy
    env = DummyVecEnv([lambda: TransferWrapper(MediatedInteractionEnv("target", spec.world), strategy)])
    features = make_features(spec.representation, spec.representation_params, spec.representation_target)
    learner = SB3Learner.of(spec.algorithm, spec.algorithm_params, features, spec.world, streams.learner_seed, env=env)
    # SB3 seeded the env's first reset with the learner's seed: use the run's env stream, as
    # run.py's loop does (the same target tasks and action noise for every learner of a seed).
    env.seed(streams.env_seed)
    curve = Curve(spec, streams, on_evaluation)
    callback = _RunCallback(spec, curve, learner, strategy, progress, progress_every or curve.every)
    try:
        learner.model.learn(total_timesteps=spec.budget, callback=callback)
    except ValueError:
        # A diverged PPO policy fails in torch.distributions (non-finite logits) mid-rollout.
        reason = learner.divergence()
        if reason is None:
            raise
        curve.failure = f"diverged by step {learner.model.num_timesteps}: {reason}"
    wall = curve.stop()
    if on_finish is not None:
        on_finish(learner)
    return run_result(spec, curve, strategy, learner.stats, callback.source_phase_end,
                      callback.first_target_reward, wall)


class _RunCallback(BaseCallback):
    """Called by SB3 after every learning step (its ``num_timesteps`` is the step count)."""

    def __init__(self, spec: RunSpec, curve: Curve, learner: SB3Learner, strategy,
                 progress: ProgressFn | None, progress_every: int):
        super().__init__(verbose=0)
        self.spec, self.curve, self.learner, self.strategy = spec, curve, learner, strategy
        self.progress, self.progress_every = progress, progress_every
        self.in_source_phase = not strategy.done
        self.source_phase_end: int | None = None
        self.first_target_reward: int | None = None

    def _on_step(self) -> bool:
        step, curve = self.num_timesteps, self.curve
        info, reward = self.locals["infos"][0], self.locals["rewards"][0]
        if reward > 0 and not info["source_phase"] and self.first_target_reward is None:
            self.first_target_reward = step
        if self.in_source_phase and self.strategy.done:
            self.in_source_phase, self.source_phase_end = False, step
        if self.locals["dones"][0]:
            self.learner.episodes += 1
        if step % curve.every == 0:
            # A diverged policy cannot even be evaluated (non-finite logits): check first.
            curve.check(step, self.learner)
            if curve.failure is None:
                curve.evaluate(step, self.learner)
        if self.progress is not None and step % self.progress_every == 0:
            self.progress(step, self.spec.budget)
        return step < self.spec.budget and curve.failure is None
