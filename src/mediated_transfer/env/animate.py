"""Write an animation (GIF) of one episode, so a person can watch a policy act.

    python -m mediated_transfer.env.animate --scenario target --policy scripted \\
        --out reports/episode.gif --seed 1
    python -m mediated_transfer.env.animate --run <run folder> --seed 3 --out reports/trained.gif
    python -m mediated_transfer.env.animate --env tool_frame --seed 1 --out reports/tool_frame.gif

A policy is a callable observation -> action; ``POLICIES`` maps each name to a factory
``(env, seed) -> policy``. Add an entry to offer more. ``--run`` shows instead the greedy
policy of a run's saved learner (saved_learner.py), in the run's world.
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Callable
from pathlib import Path

import numpy as np
from PIL import Image

from .config import WorldConfig
from .mediated_env import ACTION_NAMES, NUM_ACTIONS, MediatedInteractionEnv
from .scripted import ScriptedDirectPolicy, ScriptedToolPolicy
from .task import SCENARIOS

Policy = Callable[[np.ndarray], int]


def _scripted(env: MediatedInteractionEnv, seed: int) -> Policy:
    # The tool policy solves both scenarios (a target in reach is pushed directly).
    return ScriptedToolPolicy(env) if env.scenario == "target" else ScriptedDirectPolicy(env)


def _random(env: MediatedInteractionEnv, seed: int) -> Policy:
    rng = np.random.default_rng(seed)
    return lambda observation: int(rng.integers(NUM_ACTIONS))


POLICIES: dict[str, Callable[[MediatedInteractionEnv, int], Policy]] = {
    "scripted": _scripted,
    "random": _random,
}


def record_episode(
    env: MediatedInteractionEnv, policy: Policy, seed: int | None = None, options: dict | None = None
) -> tuple[list[np.ndarray], dict]:
    """Frames of one episode (the start and every step) and a summary of how it went."""
    if env.render_mode != "rgb_array":
        raise ValueError('record_episode needs an environment made with render_mode="rgb_array"')
    observation, info = env.reset(seed=seed, options=options)
    frames, total, actions = [env.render()], 0.0, []
    terminated = truncated = False
    while not (terminated or truncated):
        action = int(policy(observation))
        actions.append(ACTION_NAMES[action])
        observation, reward, terminated, truncated, info = env.step(action)
        total += reward
        frames.append(env.render())
    return frames, {
        "steps": env.elapsed_steps,
        "return": total,
        "is_success": bool(info["is_success"]),
        "actions": actions,
    }


def save_gif(frames: list[np.ndarray], path: str | Path, fps: float = 4.0) -> Path:
    """Write ``frames`` as a looping GIF; the last frame is held a little longer."""
    if not frames:
        raise ValueError("no frames to write")
    if not fps > 0:
        raise ValueError(f"fps must be > 0, got {fps}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    images = [Image.fromarray(frame) for frame in frames]
    duration = [round(1000 / fps)] * len(images)
    duration[-1] = 4 * duration[-1]
    images[0].save(path, save_all=True, append_images=images[1:], duration=duration, loop=0)
    return path


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description="Write a GIF of one episode.")
    parser.add_argument("--scenario", choices=SCENARIOS, default="target")
    parser.add_argument("--policy", choices=sorted(POLICIES), default=None, help="default: scripted")
    parser.add_argument("--run", default=None,
                        help="a run's folder: its saved learner's greedy policy, in the run's world")
    parser.add_argument("--env", default=None,
                        help="a named world (an env option: default, tool_frame, long_hook, ...)")
    parser.add_argument("--out", default="reports/episode.gif")
    parser.add_argument("--seed", type=int, default=0, help="seeds the task, the noise, the policy")
    parser.add_argument("--noise", type=float, default=None,
                        help="action noise (default: the config's, 0.1)")
    parser.add_argument("--fps", type=float, default=4.0)
    args = parser.parse_args(argv)

    config, label = WorldConfig(), args.policy or "scripted"
    if args.run is not None:
        if args.policy is not None:
            parser.error("--run shows the run's learner: leave out --policy")
        from ..saved_learner import SavedLearnerError, greedy_policy

        try:
            learned, spec = greedy_policy(args.run)
        except SavedLearnerError as error:
            raise SystemExit(f"Cannot animate: {error}") from None
        config, label = spec.world, f"trained ({spec.describe()})"
    if args.env is not None:
        if args.run is not None:
            parser.error("--run shows the run's learner in the run's world: leave out --env")
        from ..config.compose import ConfigError
        from ..config.worlds import named_world

        try:
            config = named_world(args.env)
        except ConfigError as error:
            raise SystemExit(f"Cannot animate: {error}") from None
    if args.noise is not None:
        config = dataclasses.replace(config, action_noise=args.noise)
    env = MediatedInteractionEnv(args.scenario, config, render_mode="rgb_array")
    policy = learned if args.run is not None else POLICIES[label](env, args.seed)
    frames, summary = record_episode(env, policy, seed=args.seed)
    path = save_gif(frames, args.out, args.fps)
    outcome = "success" if summary["is_success"] else "no success"
    print(f"{path}: {label} policy on a {args.scenario} task, {outcome} "
          f"after {summary['steps']} steps")
    return summary


if __name__ == "__main__":
    main()
