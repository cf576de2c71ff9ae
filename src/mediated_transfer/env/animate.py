"""Write an animation (GIF) of one episode, so a person can watch a policy act.

    python -m mediated_transfer.env.animate --scenario target --policy scripted \\
        --out reports/episode.gif --seed 1
    python -m mediated_transfer.env.animate --run <run folder> --seed 3 --out reports/trained.gif
    python -m mediated_transfer.env.animate --env tool_frame --seed 1 --out reports/tool_frame.gif
    PYTHONPATH=examples/worlds python -m mediated_transfer.env.animate --env rake \
        --out reports/rake.gif hydra.searchpath=[pkg://my_worlds.conf]

A policy is a callable observation -> action; ``POLICIES`` maps each name to a factory
``(world, env, seed) -> policy``. Add an entry to offer more. ``--run`` shows instead the
greedy policy of a run's saved learner (saved_learner.py), in the run's world. ``--env`` takes
any env option, a plugin's too (its search path as a trailing Hydra override, with env keys).
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Callable
from pathlib import Path

import numpy as np
from PIL import Image

from .config import WorldConfig
from .task import SCENARIOS

Policy = Callable[[np.ndarray], int]


def _scripted(world, env, seed: int) -> Policy:
    make = getattr(world, "scripted_policy", None)
    if make is None:
        raise ValueError(f"{type(world).__name__} has no scripted policy (scripted_policy); use --policy random")
    return make(env, seed)


def _random(world, env, seed: int) -> Policy:
    rng = np.random.default_rng(seed)
    return lambda observation: int(rng.integers(world.num_actions))


POLICIES: dict[str, Callable[..., Policy]] = {
    "scripted": _scripted,
    "random": _random,
}


def record_episode(
    env, policy: Policy, seed: int | None = None, options: dict | None = None, action_names=None
) -> tuple[list[np.ndarray], dict]:
    """Frames of one episode (the start and every step) and a summary of how it went
    (``action_names``: the world's; None: the paper's)."""
    if action_names is None:
        from .mediated_env import ACTION_NAMES as action_names
    if env.render_mode != "rgb_array":
        raise ValueError('record_episode needs an environment made with render_mode="rgb_array"')
    observation, info = env.reset(seed=seed, options=options)
    frames, total, actions = [env.render()], 0.0, []
    terminated = truncated = False
    while not (terminated or truncated):
        action = int(policy(observation))
        actions.append(action_names[action])
        observation, reward, terminated, truncated, info = env.step(action)
        total += reward
        frames.append(env.render())
    return frames, {
        "steps": env.unwrapped.elapsed_steps,
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
    parser.add_argument("overrides", nargs="*", metavar="KEY=VALUE",
                        help="Hydra overrides of --env's world: hydra.searchpath=[pkg://<package>.conf], env.<key>=...")
    args = parser.parse_args(argv)
    if args.overrides and args.env is None:
        parser.error("overrides apply to --env's world: name one with --env")

    from .door import build_world

    world, label = build_world(None, WorldConfig()), args.policy or "scripted"
    if args.run is not None:
        if args.policy is not None:
            parser.error("--run shows the run's learner: leave out --policy")
        from ..saved_learner import SavedLearnerError, greedy_policy

        try:
            learned, spec = greedy_policy(args.run)
        except SavedLearnerError as error:
            raise SystemExit(f"Cannot animate: {error}") from None
        world, label = spec.make_world(), f"trained ({spec.describe()})"
    if args.env is not None:
        if args.run is not None:
            parser.error("--run shows the run's learner in the run's world: leave out --env")
        from ..config.worlds import world_of_option

        try:
            world = world_of_option(args.env, args.overrides)
        except ValueError as error:  # ConfigError too: an unknown option or key, in one line
            raise SystemExit(f"Cannot animate: {error}") from None
        if args.policy is None and getattr(world, "scripted_policy", None) is None:
            label = "random"  # a world without a scripted policy: watch it act at random
    if args.noise is not None:
        world = type(world)(dataclasses.replace(world.config, action_noise=args.noise))
    env = world.make_env(args.scenario, render_mode="rgb_array")
    try:
        policy = learned if args.run is not None else POLICIES[label](world, env, args.seed)
    except ValueError as error:
        raise SystemExit(f"Cannot animate: {error}") from None
    frames, summary = record_episode(env, policy, seed=args.seed, action_names=world.action_names)
    path = save_gif(frames, args.out, args.fps)
    outcome = "success" if summary["is_success"] else "no success"
    print(f"{path}: {label} policy on a {args.scenario} task, {outcome} "
          f"after {summary['steps']} steps")
    return summary


if __name__ == "__main__":
    main()
