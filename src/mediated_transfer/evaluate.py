"""Evaluate a run's saved learner on N target tasks: its greedy policy's <R> and success rate.

    python -m mediated_transfer.evaluate --run multirun/table2_rbf/paper/regular_50/seed=3
    python -m mediated_transfer.evaluate --run <folder> --episodes 1000 --seed 100

The evaluation is the run's own (recorder.evaluate: greedy policy, the run's world and action
noise). Tasks and noise come from ``--seed`` as a run derives them from its seed, so the
defaults (the run's seed and its number of evaluation episodes) repeat the run's last
evaluation point exactly; another seed gives tasks the run was never evaluated on.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .saved_learner import SavedLearnerError, load_learner


@dataclass(frozen=True)
class Evaluation:
    mean_reward: float
    success_rate: float
    episodes: int
    seed: int


def evaluate_saved(folder: str, episodes: int | None = None,
                   seed: int | None = None) -> tuple[Evaluation, str]:
    """Evaluate the learner saved in ``folder``; return the result and the run's description."""
    from .recorder import _EVAL_NOISE_STREAM, _EVAL_TASK_STREAM, _stream_seed, evaluate

    learner, spec = load_learner(folder)
    episodes = spec.eval_episodes if episodes is None else episodes
    seed = spec.seed if seed is None else seed
    # The run's streams (run.execute_run): the same seed gives the same tasks and noise.
    world = spec.make_world()
    tasks = world.sample_tasks("target", episodes, np.random.default_rng(_stream_seed(seed, _EVAL_TASK_STREAM)))
    env = world.make_env("target")
    reward, success = evaluate(learner, env, tasks, _stream_seed(seed, _EVAL_NOISE_STREAM))
    return Evaluation(reward, success, episodes, seed), spec.describe()


def main(argv: Sequence[str] | None = None) -> Evaluation:
    parser = argparse.ArgumentParser(
        prog="python -m mediated_transfer.evaluate",
        description="Evaluate a run's saved learner (greedy policy) on N target tasks.")
    parser.add_argument("--run", required=True, help="the run's folder (holds learner.npz or learner.pt)")
    parser.add_argument("--episodes", type=int, default=None,
                        help="target tasks to evaluate on (default: the run's eval_episodes)")
    parser.add_argument("--seed", type=int, default=None,
                        help="seeds the tasks and the action noise (default: the run's seed, "
                             "which repeats its last evaluation point)")
    args = parser.parse_args(argv)
    if args.episodes is not None and args.episodes < 1:
        parser.error(f"--episodes must be >= 1, got {args.episodes}")
    if args.seed is not None and args.seed < 0:
        parser.error(f"--seed must be >= 0, got {args.seed}")
    try:
        result, described = evaluate_saved(args.run, args.episodes, args.seed)
    except SavedLearnerError as error:
        raise SystemExit(f"Cannot evaluate: {error}") from None
    print(f"{args.run}: {described}, greedy on {result.episodes} target tasks (seed {result.seed}): "
          f"<R> = {result.mean_reward:.2f}, success rate {result.success_rate:.1%}")
    recorded = _last_point(args.run, result)
    if recorded is not None:
        print(f"(the same tasks and noise as the run's last evaluation point, which recorded "
              f"<R> = {recorded[0]:.2f}, success rate {recorded[1]:.1%})")
    return result


def _last_point(folder: str, result: Evaluation) -> tuple[float, float] | None:
    """The run's recorded last evaluation point, if ``result`` was measured the same way."""
    from .results import DamagedResult, RunResult

    if not RunResult.exists(folder):
        return None
    try:
        run = RunResult.read(folder)
    except DamagedResult as damaged:
        print(f"(no recorded point to compare with: {damaged})", file=sys.stderr)
        return None
    scale = run.config.get("scale", {}) if run.config else {}
    if not run.mean_reward or (run.seed, scale.get("eval_episodes")) != (result.seed, result.episodes):
        return None
    return run.mean_reward[-1], run.success_rate[-1]


if __name__ == "__main__":
    main(sys.argv[1:])
