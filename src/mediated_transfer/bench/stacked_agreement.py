"""``python -m mediated_transfer.bench.stacked_agreement``: do the stacked networks (the GPU
path, ``lockstep.device=cuda``) learn what the single-run path learns? Batched products sum in
another order, so their curves are not the single runs' bit for bit; this runs the same seeds
of one Table IV row both ways and compares the statistics: mean L_R, runs that never learn,
the per-run time to threshold, each with the ratio stacked / single and its 95 % bootstrap
interval. On the CPU here (``--device cpu``) the stacked path is ~2x slower per network than the
single runs; on a GPU it is the path Table IV would take.

Not part of ``make bench`` (minutes to hours): ``--scale quick`` (150k steps, 10 x 20 evaluation
episodes) and 10 seeds take about an hour of one core.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import replace

import numpy as np

SEEDS = range(3000, 3010)
"""Neither table seeds (0-19), tuning seeds (1000-1012) nor the ablation's (2000-2019)."""


def run(cell: str, scale: str, seeds, device: str) -> dict:
    from ..config.compose import compose_config
    from ..config.spec import run_spec
    from ..learners.dqn import DQNConfig
    from ..lockstep.run import execute_lockstep
    from ..lockstep.stacked import StackedDQN
    from ..metrics import first_point_at_threshold
    from ..reporting.intervals import ratio_of_means, ratio_of_medians
    from ..run import RunStreams, execute_run

    cfg = compose_config(["experiment=table4_dnn", f"cell={cell}", f"scale={scale}", "tracking=none"])
    base = run_spec(cfg)
    specs = [replace(base, seed=s) for s in seeds]
    started = time.perf_counter()
    single = [execute_run(s) for s in specs]
    single_s = time.perf_counter() - started
    group = StackedDQN(DQNConfig(**base.algorithm_params), [RunStreams.of(s).learner_seed for s in specs],
                       device=device)
    started = time.perf_counter()
    stacked = execute_lockstep(specs, group=group)
    stacked_s = time.perf_counter() - started

    def summary(results):
        losses = [r.reward_loss for r in results]
        times = [math.inf if r.time_to_threshold is None else r.time_to_threshold for r in results]
        never = sum(first_point_at_threshold(r.mean_reward, base.threshold) is None for r in results)
        return losses, times, never

    (l1, t1, n1), (l2, t2, n2) = summary(single), summary(stacked)
    return {
        "cell": cell, "scale": scale, "seeds": list(seeds), "device": device,
        "single": {"reward_loss": l1, "time_to_threshold": t1, "never_learn": n1, "seconds": single_s},
        "stacked": {"reward_loss": l2, "time_to_threshold": t2, "never_learn": n2, "seconds": stacked_s},
        "reward_loss_ratio": ratio_of_means(l2, l1),
        "time_to_threshold_ratio": ratio_of_medians(t2, t1),
        "identical_curves": sum(a.mean_reward == b.mean_reward for a, b in zip(single, stacked)),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.bench.stacked_agreement",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--cell", default="regular_50")
    parser.add_argument("--scale", default="quick")
    parser.add_argument("--seeds", type=int, default=len(SEEDS), help=f"how many of seeds {SEEDS.start}...")
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)
    result = run(args.cell, args.scale, range(SEEDS.start, SEEDS.start + args.seeds), args.device)
    s, t = result["single"], result["stacked"]
    fmt = lambda r: f"{r[0]:.2f} [{r[1]:.2f}, {r[2]:.2f}]"  # noqa: E731
    print(f"{args.cell}, scale={args.scale}, {args.seeds} seeds, stacked on {args.device}:\n"
          f"  mean L_R: single {np.mean(s['reward_loss']):.1f}, stacked {np.mean(t['reward_loss']):.1f}; "
          f"ratio {fmt(result['reward_loss_ratio'])}\n"
          f"  median time to threshold: single {np.median(s['time_to_threshold']):.0f}, stacked "
          f"{np.median(t['time_to_threshold']):.0f}; ratio {fmt(result['time_to_threshold_ratio'])}\n"
          f"  runs that never learn: single {s['never_learn']}, stacked {t['never_learn']}; curves identical: "
          f"{result['identical_curves']} of {args.seeds}\n"
          f"  time: single runs {s['seconds']:.0f} s, stacked group {t['seconds']:.0f} s", flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(result, fh, indent=1, default=float)
    return 0


if __name__ == "__main__":
    sys.exit(main())
