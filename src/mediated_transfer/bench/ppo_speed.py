"""PPO's speed through the run loop: learning steps/s with K training environments
(``algorithm.n_envs``, run_sb3.py) against one, and the projected wall time of Table V (PPO).

Each run is a real one: SB3 PPO (provisional values, ``tuned=provisional``, representation network) on the paper's
world with regular transfer (row ``regular_50``, its source phase included), through the run
loop and its recorder, as a table's run goes. Every K keeps SB3's default rollout of 2,048
learning steps (``n_steps`` = 2048 / K per environment), so that K changes how a rollout is
collected, not how much each update learns from. The runs of every K alternate, round by round,
in this one process, so the machine's load hits them alike; a run's rate is timed over whole
rollouts (collection and update) after its first, and the ratio to K = 1 is taken per round
(medians are reported).

Table V is projected as projection.py projects Tables II-IV: its rows x seeds (those of
Table IV: 11 rows x 20 seeds at the paper's scale), each run ``setup + budget / (steps/s) +
eval_points x (s per evaluation point) + job overhead``, divided by this machine's cores (one run
per core). The evaluation point is timed once, after the first round's base run (100
target-task episodes of a barely trained policy, which mostly run to their step limit: an upper
bound). Beside the comparison, each round also times Table V as it runs
(``experiment=table5_ppo``: Table I's tuned values, their environments and rollout), and the
table is projected from that rate too.
"""

from __future__ import annotations

import os
import statistics
from dataclasses import replace

from .projection import JOB_OVERHEAD_S, timed_run

KS = (1, 2, 4, 8, 16)
"""Numbers of environments compared (each divides the rollout)."""
RECOMMENDED_K = 8
"""The K the bench projects Table V with: it takes the collection from ~400 to ~70 us per learning
step, nearly all that more environments give (the rest is PPO's update, ~80 % of a K = 8 run),
with rollouts of 256 steps per environment (several whole episodes) and at most 7 episodes in
flight at the hand-over (docs/benchmarks.md, "PPO with several environments")."""
ROLLOUT = 2048
"""Learning steps per rollout, every K (SB3's default n_steps with one environment)."""
CELL = "regular_50"
TABLE = "table4_dnn"
"""Table V has Table IV's rows and seeds (the DNN's sensor vector, PPO as its learner)."""
TABLE5 = "table5_ppo"
"""Table V itself: what "as it runs" composes (its tuned values, environments and rollout)."""
PROBE_SEED = 10_000
"""Not a table seed (0-19) nor a tuning seed (1000-1009): the probe measures speed only."""
ROUNDS = 3


def _spec(overrides: list[str], rollout: int | None, rollouts: int, eval_episodes: int | None):
    """The paper-scale run of ``overrides`` and its probe: ``rollouts`` timed rollouts of
    ``rollout`` learning steps (None: the composed n_steps x n_envs), then half of one, and one
    evaluation point of ``eval_episodes`` (None: the paper's)."""
    from ..config.compose import compose_config
    from ..config.spec import run_spec

    cfg = compose_config([f"cell={CELL}", "scale=paper", f"seed={PROBE_SEED}", "tracking=none", *overrides])
    rollout = rollout or int(cfg.algorithm.n_steps) * int(cfg.algorithm.n_envs)
    paper = run_spec(cfg)
    # Marks at every rollout's end; the run stops half a rollout after the last timed one.
    budget = (rollouts + 1) * rollout + rollout // 2
    episodes = paper.eval_episodes if eval_episodes is None else eval_episodes
    probe = replace(paper, budget=budget, eval_points=1, eval_episodes=episodes)
    return paper, probe, rollout


def _timed(overrides: list[str], rollout: int | None, rollouts: int, eval_episodes: int | None) -> dict:
    """One short run: its learning steps/s over ``rollouts`` whole rollouts after the first, and
    the seconds of its one evaluation point."""
    paper, spec, rollout = _spec(overrides, rollout, rollouts, eval_episodes)
    result, marks, total = timed_run(spec, rollout)
    first, last = rollout, (rollouts + 1) * rollout
    learn = spec.budget / result.learning_steps_per_s
    return {"steps_per_s": (last - first) / (marks[last] - marks[first]),
            "eval_s_per_point": result.wall_time_s - learn, "setup_s": total - result.wall_time_s,
            "paper_budget": paper.budget, "paper_eval_points": paper.eval_points,
            "eval_episodes": spec.eval_episodes, "paper_eval_episodes": paper.eval_episodes,
            "source_phase_end": result.source_phase_end, "rollout": rollout}


def measure(n_envs: int, rollouts: int, eval_episodes: int | None = 1) -> dict:
    """One short run with ``n_envs`` environments on the provisional values, the rollout held at
    SB3's 2,048 learning steps."""
    overrides = [f"experiment={TABLE}", "algorithm=sb3_ppo", "tuned=provisional",
                 f"algorithm.n_envs={n_envs}", f"algorithm.n_steps={ROLLOUT // n_envs}"]
    return {"n_envs": n_envs, **_timed(overrides, ROLLOUT, rollouts, eval_episodes)}


def measure_table5(rollouts: int) -> dict:
    """One short run as Table V runs: its experiment's learner, tuned values and environments."""
    return _timed([f"experiment={TABLE5}"], None, rollouts, 1)


def project_table(steps_per_s: float, eval_s_per_point: float, setup_s: float, runs: int, cores: int,
                  budget: int, eval_points: int) -> dict:
    """Table V's projected CPU and wall hours on ``cores`` (one run per core)."""
    run_s = setup_s + budget / steps_per_s + eval_points * eval_s_per_point + JOB_OVERHEAD_S
    return {"run_s": run_s, "cpu_hours": runs * run_s / 3600, "wall_hours": runs * run_s / cores / 3600}


def run(steps: int | None = None, ks: tuple[int, ...] = KS, rounds: int = ROUNDS, cores: int | None = None,
        verbose: bool = True, eval_episodes: int | None = None) -> dict:
    """``steps``: learning steps timed per run (whole rollouts of 2,048; default 3 rollouts);
    ``eval_episodes``: episodes the evaluation point is timed over (default the paper's point),
    scaled to the paper's point."""
    from .projection import table_rows

    # 0 episodes would time nothing and divide by zero when scaled to the paper's point.
    if eval_episodes is not None and eval_episodes < 1:
        raise ValueError("eval_episodes must be a positive number of episodes, or None for the paper's; "
                         f"got {eval_episodes}")
    rollouts = max(1, (steps or 3 * ROLLOUT) // ROLLOUT)
    cores = cores or len(os.sched_getaffinity(0))
    cells, seeds = table_rows(TABLE)
    table_runs = len(cells) * seeds
    if verbose:
        print(f"PPO ({CELL}, paper world, provisional values, rollout {ROLLOUT}): {rounds} rounds of "
              f"{rollouts} timed rollouts per K in {', '.join(map(str, ks))}...", flush=True)
    per_round: list[dict[int, dict]] = []
    as_run: list[dict] = []
    base = ks[0]
    for i in range(rounds):
        # The first round's base run also times the evaluation point; the rate is timed over
        # rollouts, before it.
        per_round.append({k: measure(k, rollouts, eval_episodes=eval_episodes if (i, k) == (0, base) else 1)
                          for k in ks})
        as_run.append(measure_table5(rollouts))
    evaluation = per_round[0][base]
    eval_s = evaluation["eval_s_per_point"] * evaluation["paper_eval_episodes"] / evaluation["eval_episodes"]
    result: dict = {"cores": cores, "rollout": ROLLOUT, "cell": CELL, "rounds": rounds, "by_k": {}}
    for k in ks:
        rates = [r[k]["steps_per_s"] for r in per_round]
        ratios = [r[k]["steps_per_s"] / r[base]["steps_per_s"] for r in per_round]
        result["by_k"][k] = {"steps_per_s": statistics.median(rates), "ratio_to_k1": statistics.median(ratios),
                             "ratios": ratios}
    setup = statistics.median(r[base]["setup_s"] for r in per_round)
    projected = {}
    for k in sorted({base, RECOMMENDED_K} & set(ks)):
        # K = 1's rate times K's ratio (taken pair by pair, it is the steadier figure under load).
        rate = result["by_k"][base]["steps_per_s"] * result["by_k"][k]["ratio_to_k1"]
        projected[k] = project_table(rate, eval_s, setup,
                                     table_runs, cores, evaluation["paper_budget"],
                                     evaluation["paper_eval_points"])
    tuned_rate = statistics.median(r["steps_per_s"] for r in as_run)
    tuned_ratio = statistics.median(t["steps_per_s"] / r[base]["steps_per_s"] for t, r in zip(as_run, per_round))
    as_tuned = {"steps_per_s": tuned_rate, "ratio_to_k1": tuned_ratio, "rollout": as_run[0]["rollout"],
                **project_table(result["by_k"][base]["steps_per_s"] * tuned_ratio, eval_s,
                                setup, table_runs, cores, evaluation["paper_budget"], evaluation["paper_eval_points"])}
    result.update({"eval_s_per_point": eval_s, "table_runs": table_runs,
                   "recommended_k": RECOMMENDED_K, "table5": projected, "table5_as_run": as_tuned})
    if verbose:
        for k in ks:
            r = result["by_k"][k]
            print(f"  n_envs={k:>2}: {r['steps_per_s']:,.0f} learning steps/s, x{r['ratio_to_k1']:.2f} vs n_envs={base} "
                  f"(per round: {', '.join(f'{x:.2f}' for x in r['ratios'])})", flush=True)
        print(f"  an evaluation point ({evaluation['paper_eval_episodes']} episodes): {eval_s:.1f} s", flush=True)
        for k, p in projected.items():
            print(f"  Table V ({table_runs} paper-scale runs) with n_envs={k}: a run ~{p['run_s']:.0f} s -> "
                  f"{p['cpu_hours']:.1f} CPU-h, {p['wall_hours']:.1f} h on {cores} cores", flush=True)
        t = as_tuned
        print(f"  Table V as it runs ({TABLE5}: tuned values, rollout {t['rollout']}): {t['steps_per_s']:,.0f} "
              f"learning steps/s, x{t['ratio_to_k1']:.2f} vs provisional n_envs={base}; a run ~{t['run_s']:.0f} s -> "
              f"{t['cpu_hours']:.1f} CPU-h, {t['wall_hours']:.1f} h on {cores} cores", flush=True)
    return result


if __name__ == "__main__":
    run()
