"""Speed of the deep Q-learner with Table I's values, and what lockstep groups gain.

1. Where a learning step's time goes (the single-run path, fast kernels, past the warm-up):
   the environment step, acting, the replay buffer (store, sample), the update's matrix
   products (online and target forward, backward), Adam with clipping, the rest of the update
   (TD target, head and ReLU kernels, call overhead), and the loop's own Python: each timed
   alone on the run's own state, the loop's share as what the whole step leaves.
2. Learning steps/s per network of K runs of one cell (Table IV's scaffolded 15, Table I's
   values) stepped together, against the same K runs one after the other (today's single-run
   path), both timed past the warm-up through their real loops (run.execute_run,
   lockstep.run.execute_lockstep): the CPU group (each run's own fast learner) and the stacked
   networks (the GPU path: batched products and one Adam pass; on this CPU, and on a GPU when
   torch sees one). The three alternate in rounds (medians of per-round ratios), so load from
   other processes hits them alike.
3. What that makes of Table IV (220 runs of 500k steps) on this machine's cores.
Ratios within one run; aims: a group's steps/s per network >= 3x a single run's, Table IV
<= 3.5 h on 2 cores.
"""

from __future__ import annotations

import os
import statistics
import time
from dataclasses import replace

import numpy as np
import torch

ROUNDS = 3
PROBE_SEED = 10_000
"""Not a table seed (0-19) nor a tuning seed: the bench measures speed only."""
CELL = "scaffolded_15"
TABLE_IV_RUNS = 220


def tuned_spec(steps: int):
    """Table IV's configuration of ``CELL`` with Table I's DQN values, ``steps`` learning steps
    past the warm-up and one small evaluation point."""
    from ..config.compose import compose_config
    from ..config.spec import run_spec

    cfg = compose_config(["experiment=table4_dnn", f"cell={CELL}", "scale=paper", f"seed={PROBE_SEED}",
                          "tracking=none"])
    spec = run_spec(cfg)
    warm_up = int(spec.algorithm_params["learning_starts"])
    return replace(spec, budget=warm_up + steps, eval_points=1, eval_episodes=10), warm_up


def _per_call_us(fn, repeats: int) -> float:
    start = time.perf_counter()
    for _ in range(repeats):
        fn()
    return (time.perf_counter() - start) / repeats * 1e6


def breakdown(spec, warm_up: int, steps: int) -> dict:
    """Microseconds per learning step of each part, on a learner past its warm-up."""
    from ..env.mediated_env import MediatedInteractionEnv
    from ..learners.dqn import DQNConfig, DQNLearner
    from .dqn_speed import _OurLoop

    config = DQNConfig(**spec.algorithm_params)
    learner, env = DQNLearner(config, seed=PROBE_SEED), MediatedInteractionEnv("target", spec.world)
    experiment_loop = _OurLoop(learner, env, PROBE_SEED)  # the DQN bench's loop: act, step, observe

    def loop(n: int) -> float:
        return experiment_loop.advance(n) / n * 1e6

    loop(warm_up + 500)  # past learning_starts and most of the epsilon decay
    rounds = [_parts(loop, learner, env, config, steps) for _ in range(ROUNDS)]
    parts = {k: statistics.median(r[k] for r in rounds) for k in rounds[0]}
    parts["update_rest"] = parts["update"] - parts["update_products"] - parts["update_adam"]
    parts["loop_python"] = parts["step"] - sum(parts[k] for k in ("env", "act", "buffer_store",
                                                                 "buffer_sample", "update"))
    return parts


def _parts(loop, learner, env, config, steps: int) -> dict:
    """One round of the breakdown's timings."""
    from ..learners.dqn import DQNLearner
    from ..learners.dqn_kernels import _adam_step
    from .dqn_speed import products_alone_s

    parts = {"step": loop(steps)}
    rng = np.random.default_rng(0)
    actions = rng.integers(0, 11, steps)
    state = env.reset(seed=1)[0]

    def env_step(i=iter(actions)):
        _, _, terminated, truncated, _ = env.step(int(next(i)))
        if terminated or truncated:
            env.reset()

    parts["env"] = _per_call_us(env_step, steps)
    parts["act"] = _per_call_us(lambda: learner.act(state), steps)
    scratch = DQNLearner(config, seed=PROBE_SEED)  # storing: not into the learner's buffer
    parts["buffer_store"] = _per_call_us(lambda: scratch.buffer.add(state, 1, 0.0, state, False), steps)
    parts["buffer_sample"] = _per_call_us(lambda: learner.buffer.sample(rng), steps)
    batch = learner.buffer.sample(rng)
    update = learner.update
    parts["update"] = _per_call_us(lambda: update(batch), steps // 2)
    parts["update_products"] = products_alone_s(config, repeats=steps // 4) * 1e6
    params, grad, mean, sq = update._params_np, *update._adam_np
    zero = np.zeros_like(grad)  # a zero gradient: the same pass, the weights unchanged

    def adam():
        _adam_step(params, zero, mean, sq, np.float32(0.0), np.float32(config.adam_beta1),
                   np.float32(config.adam_beta2), np.float32(config.adam_epsilon), np.float32(1.0),
                   float(config.max_grad_norm or 0.0))

    torch.set_flush_denormal(True)
    parts["update_adam"] = _per_call_us(adam, steps // 2)
    torch.set_flush_denormal(False)
    del grad
    return parts


def steps_per_network(specs, warm_up: int, lockstep: bool, group_of=None) -> float:
    """Learning steps/s per network past the warm-up: the runs one after the other, or as one
    lockstep group (``group_of(specs)`` builds its learners; default the CPU group)."""
    from ..lockstep.run import RunHooks, execute_lockstep
    from ..run import execute_run
    from .projection import steady_rate

    budget, every = specs[0].budget, 500
    if lockstep:
        marks: dict[int, float] = {}
        hooks = [RunHooks(progress=(lambda s, b: marks.__setitem__(s, time.perf_counter())) if k == 0 else None,
                          progress_every=every) for k in range(len(specs))]
        execute_lockstep(specs, hooks, group=None if group_of is None else group_of(specs))
        return len(specs) * steady_rate(marks, warm_up, budget)
    seconds = 0.0
    for spec in specs:
        marks = {}
        execute_run(spec, progress=lambda s, b: marks.__setitem__(s, time.perf_counter()), progress_every=every)
        seconds += 1.0 / steady_rate(marks, warm_up, budget)
    return len(specs) / seconds


def _stacked(device: str):
    def group_of(specs):
        from ..learners.dqn import DQNConfig
        from ..lockstep.stacked import StackedDQN
        from ..run import RunStreams

        return StackedDQN(DQNConfig(**specs[0].algorithm_params),
                          [RunStreams.of(s).learner_seed for s in specs], device=device)
    return group_of


def run(steps: int | None = None, runs: int = 4, verbose: bool = True) -> dict:
    steps = steps or 2_000
    torch.set_num_threads(1)
    spec, warm_up = tuned_spec(steps)
    parts = breakdown(spec, warm_up, steps)
    specs = [replace(spec, seed=PROBE_SEED + k) for k in range(runs)]
    ways = {"single": lambda: steps_per_network(specs, warm_up, lockstep=False),
            "lockstep_cpu": lambda: steps_per_network(specs, warm_up, lockstep=True),
            "stacked_cpu": lambda: steps_per_network(specs, warm_up, lockstep=True, group_of=_stacked("cpu"))}
    if torch.cuda.is_available():  # a cell's 20 seeds at once, as lockstep.runs=null does on a GPU
        gpu_specs = [replace(spec, seed=PROBE_SEED + k) for k in range(TABLE_IV_RUNS // 11)]
        ways["stacked_cuda_20"] = lambda: steps_per_network(gpu_specs, warm_up, lockstep=True,
                                                            group_of=_stacked("cuda"))
    measured = [{name: way() for name, way in ways.items()} for _ in range(ROUNDS)]
    rates = {name: statistics.median(m[name] for m in measured) for name in ways}
    ratios = {name: statistics.median(m[name] / m["single"] for m in measured) for name in ways if name != "single"}
    from ..learners.dqn import DQNConfig, update_flops
    from .dqn_speed import matmul_gflops

    flops = update_flops(DQNConfig(**spec.algorithm_params))
    matmul = statistics.median(matmul_gflops() for _ in range(3))
    cores = len(os.sched_getaffinity(0))
    result = {
        "cell": CELL, "runs": runs, "timed_steps_per_run": steps, "breakdown_us": parts,
        "update_flop_fraction": flops / (parts["update"] * 1e-6) / 1e9 / matmul,
        "products_flop_fraction": flops / (parts["update_products"] * 1e-6) / 1e9 / matmul,
        "matmul_gflops": matmul,
        "steps_per_s_per_network": rates,
        "ratios": ratios,
        # Learning only (evaluation is ~1 % of a tuned DQN run), every core one run or group.
        "table_iv_hours": {k: TABLE_IV_RUNS * 500_000 / v / cores / 3600 for k, v in rates.items()},
        "cores": cores,
    }
    if verbose:
        p = parts
        print(f"a tuned DQN learning step ({CELL}, past the warm-up): {p['step']:.0f} us = env "
              f"{p['env']:.0f} + act {p['act']:.0f} + buffer {p['buffer_store']:.0f}+{p['buffer_sample']:.0f} "
              f"(store+sample) + update {p['update']:.0f} [matrix products {p['update_products']:.0f}, "
              f"Adam+clip {p['update_adam']:.0f}, the rest {p['update_rest']:.0f}] + loop {p['loop_python']:.0f}",
              flush=True)
        print(f"  update: {flops / 1e6:.1f} MFLOP = {result['update_flop_fraction']:.0%} of a 512x512 "
              f"matmul's {matmul:.0f} GFLOP/s (aim >= 80%); its products alone "
              f"{result['products_flop_fraction']:.0%}", flush=True)
        line = ", ".join(f"{k} {v:,.0f}" for k, v in rates.items())
        print(f"  learning steps/s per network, {runs} runs ({ROUNDS} alternating rounds): {line}", flush=True)
        ratio = ", ".join(f"{k} {v:.2f}x" for k, v in result["ratios"].items())
        print(f"  per network vs single runs: {ratio} (aim >= 3x)", flush=True)
        hours = ", ".join(f"{k} {v:.1f} h" for k, v in result["table_iv_hours"].items())
        print(f"  Table IV's learning on {cores} cores: {hours} (aim <= 3.5 h on 2 cores)", flush=True)
    return result


if __name__ == "__main__":
    run()
