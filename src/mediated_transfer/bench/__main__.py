"""`make bench`: speed ratios of the environment and the learners, each measured in one run.

Ratios, not absolute times, are the targets (they survive a slower or busier machine):
  env:    Python per env step / its time inside Chipmunk's cpSpaceStep    (aim <= 1)
  linear: linear learner time per step / environment step                (aim <= 1)
  dqn:    our DQN learning steps/s / Stable-Baselines3 DQN steps/s       (aim >= 5)
  lockstep: a tuned DQN step's breakdown; steps/s per network of K runs stepped together
          (CPU group, stacked networks) / single runs                      (aim >= 3)
  startup: a finished sweep run again (a skip), seconds and / computing it  (aim < 1.5 s)
  ppo:    SB3 PPO learning steps/s with K environments (algorithm.n_envs) / with one, and
          Table V's (PPO) projected wall time on this machine's cores
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys

PARTS = {
    "env": "mediated_transfer.bench.env_speed",
    "linear": "mediated_transfer.bench.learner_speed",
    "dqn": "mediated_transfer.bench.dqn_speed",
    "lockstep": "mediated_transfer.bench.lockstep_speed",
    "projection": "mediated_transfer.bench.projection",
    "startup": "mediated_transfer.bench.startup_speed",
    "ppo": "mediated_transfer.bench.ppo_speed",
}
DEFAULT_STEPS = {"env": 20_000, "linear": 20_000, "dqn": 5_000, "lockstep": 2_000, "projection": None, "startup": 5,
                 "ppo": 3 * 2048}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.bench", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    # Checked below, not with `choices`: Python 3.11's argparse refuses an empty list there.
    parser.add_argument("parts", nargs="*", metavar="PART",
                        help=f"which benchmarks to run: {', '.join(PARTS)} (default: all)")
    parser.add_argument("--steps", type=int, default=None, help="steps per measurement")
    parser.add_argument("--json", default=None, help="also write the results to this JSON file")
    args = parser.parse_args(argv)
    unknown = [p for p in args.parts if p not in PARTS]
    if unknown:
        parser.error(f"unknown benchmark(s) {', '.join(unknown)}; allowed: {', '.join(PARTS)}")
    results = {}
    for part in args.parts or list(PARTS):
        print(f"== {part} ==", flush=True)
        module = importlib.import_module(PARTS[part])
        results[part] = module.run(args.steps or DEFAULT_STEPS[part])
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=2, default=float)
    return 0


if __name__ == "__main__":
    sys.exit(main())
