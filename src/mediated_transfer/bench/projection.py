"""How long `make reproduce-tables SCALE=paper` would take on this machine, from real work.

For every row (cell) of each table, one short run of the real configuration (the table's
learner with its tuned values, the row's strategy and N_source, the paper's world and task
sets) is timed: ``--steps`` learning steps and one evaluation point of the paper's 100
target-task episodes. Probes run as many at a time as the sweep would (one per core), in fresh
processes, so they share caches and memory bandwidth as the real runs do. A run of a row is
then projected as

    setup + budget / (learning steps per s) + eval_points x (seconds per evaluation point)

and a table as the sum over its rows x seeds, divided by the cores. The learning steps/s are
timed past the learner's warm-up: the DQN does no update before ``learning_starts`` (6,335 steps
when tuned), and a run's rate over the whole probe, those cheap steps included, projected a
tuned Table IV run at 4 min where it took 6. What the projection does not see, stated so its
error is known: a short probe sees the start of learning (no learned policy yet, so evaluation
episodes run to their 100-step limit: an upper bound on evaluation; the DQN's epsilon is still
high), and the sweep's own cost per run (Hydra's job start, result and MLflow writes, about a
second) is added as ``job_overhead_s``.
"""

from __future__ import annotations

import os
import statistics
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from multiprocessing import get_context

TABLES = ("table2_rbf", "table3_fsr", "table4_dnn")
PROBE_STEPS = {"linear_q": 50_000, "dqn": 20_000}
"""Learning steps of one probe after the learner's warm-up (``--steps`` replaces both); the
DQN's steps cost ~20x more."""
MARK_EVERY = 1_000
"""The probe notes the time every this many learning steps, to time the steps past warm-up."""
PROBE_SEED = 10_000
"""Not a table seed (0-19) nor a tuning seed (1000-1009): the probe measures speed only."""
JOB_OVERHEAD_S = 1.0
"""Per run, outside the run itself: Hydra's job start, result.json, the MLflow run."""


def table_rows(experiment: str) -> tuple[list[str], int]:
    """The table's cells (its rows) and its seeds per row, at paper scale, from its config."""
    from ..config.compose import compose_config

    cfg = compose_config([f"experiment={experiment}", "scale=paper"], hydra=True)
    cells = str(cfg.hydra.sweeper.params.cell).split(",")
    return cells, int(cfg.scale.seeds)


def warm_up_steps(spec) -> int:
    """Learning steps before the learner's steady work: the DQN's ``learning_starts`` (no
    gradient update before it), 0 for the linear learners."""
    return int(spec.algorithm_params.get("learning_starts", 0))


def probe(experiment: str, cell: str, steps: int | None) -> dict:
    """Time one short run of the table's row ``cell`` (in this process)."""
    from ..config.compose import compose_config
    from ..config.spec import run_spec

    cfg = compose_config([f"experiment={experiment}", f"cell={cell}", "scale=paper",
                          f"seed={PROBE_SEED}", "tracking=none"])
    paper = run_spec(cfg)
    warm_up = warm_up_steps(paper)
    measured = steps or PROBE_STEPS[paper.algorithm]
    budget = warm_up + measured
    spec = replace(paper, budget=budget, eval_points=1)
    result, marks, total = timed_run(spec, min(MARK_EVERY, budget))
    learn = budget / result.learning_steps_per_s
    return {
        "experiment": experiment, "cell": cell, "algorithm": spec.algorithm,
        "probe_steps": budget, "warm_up_steps": warm_up,
        "steps_per_s": steady_rate(marks, warm_up, budget) or result.learning_steps_per_s,
        "eval_s_per_point": result.wall_time_s - learn,
        "setup_s": total - result.wall_time_s,
        "paper_budget": paper.budget, "paper_eval_points": paper.eval_points,
    }


def timed_run(spec, every: int):
    """``spec`` run once in this process, its source task set clustered first (as a sweep does,
    before its runs): (result, the time of every ``every``-th learning step, seconds in all)."""
    from ..run import execute_run
    from ..transfer.source_tasks import precompute_source_task_sets

    if spec.n_source and spec.cache_dir is not None:
        precompute_source_task_sets({spec.n_source}, spec.make_world(), spec.source_pool_size,
                                    spec.source_set_seed, cache_dir=spec.cache_dir)
    marks: dict[int, float] = {}

    def mark(step: int, _budget: int) -> None:
        marks[step] = time.perf_counter()

    start = time.perf_counter()
    result = execute_run(spec, progress=mark, progress_every=every)
    return result, marks, time.perf_counter() - start


def steady_rate(marks: dict[int, float], warm_up: int, budget: int) -> float | None:
    """Learning steps/s between the first mark at or past ``warm_up`` and the last before the
    probe's end (which also holds its evaluation); None when fewer than two such marks."""
    inside = sorted(step for step in marks if warm_up <= step < budget)
    if len(inside) < 2:
        return None
    first, last = inside[0], inside[-1]
    return (last - first) / (marks[last] - marks[first])


def project_run(p: dict) -> float:
    """Projected seconds of one paper-scale run of a probed row."""
    return (p["setup_s"] + p["paper_budget"] / p["steps_per_s"]
            + p["paper_eval_points"] * p["eval_s_per_point"] + JOB_OVERHEAD_S)


def project(probes: list[dict], rows: dict[str, tuple[list[str], int]], cores: int) -> dict:
    """The projected sweep from the probes of every row: per table its runs, CPU hours, wall
    hours on ``cores`` and where the time goes; the total wall hours."""
    result: dict = {"cores": cores, "tables": {}, "probes": probes}
    total_s = 0.0
    for table, (_, seeds) in rows.items():
        mine = [p for p in probes if p["experiment"] == table]
        cpu_s = sum(seeds * project_run(p) for p in mine)
        learn_s = sum(seeds * p["paper_budget"] / p["steps_per_s"] for p in mine)
        eval_s = sum(seeds * p["paper_eval_points"] * p["eval_s_per_point"] for p in mine)
        slowest = max(mine, key=project_run)
        total_s += cpu_s / cores
        result["tables"][table] = {
            "runs": seeds * len(mine), "cpu_hours": cpu_s / 3600, "wall_hours": cpu_s / cores / 3600,
            "run_s_median": statistics.median(project_run(p) for p in mine),
            "slowest_row": slowest["cell"], "slowest_run_s": project_run(slowest),
            "steps_per_s_median": statistics.median(p["steps_per_s"] for p in mine),
            "learning_share": learn_s / cpu_s, "evaluation_share": eval_s / cpu_s,
        }
    result["total_wall_hours"] = total_s / 3600
    return result


def run(steps: int | None = None, tables: tuple[str, ...] = TABLES, cores: int | None = None,
        verbose: bool = True) -> dict:
    """Probe every row of ``tables`` on ``cores`` processes and project the paper-scale sweep."""
    cores = cores or len(os.sched_getaffinity(0))
    rows = {t: table_rows(t) for t in tables}
    jobs = [(t, cell) for t in tables for cell in rows[t][0]]
    if verbose:
        print(f"probing {len(jobs)} rows ({', '.join(tables)}) on {cores} core(s)...", flush=True)
    with ProcessPoolExecutor(cores, mp_context=get_context("spawn")) as pool:
        probes = list(pool.map(probe, *zip(*jobs), [steps] * len(jobs)))
    result = project(probes, rows, cores)
    if verbose:
        for t, r in result["tables"].items():
            print(f"  {t}: {r['runs']} runs, a run ~{r['run_s_median']:.0f} s (slowest row "
                  f"{r['slowest_row']}: {r['slowest_run_s']:.0f} s; "
                  f"{r['steps_per_s_median']:,.0f} learning steps/s) -> {r['cpu_hours']:.2f} CPU-h, "
                  f"{r['wall_hours']:.2f} h on {cores} cores; learning {r['learning_share']:.0%}, "
                  f"evaluation {r['evaluation_share']:.0%} of it", flush=True)
        print(f"  make reproduce-tables SCALE=paper: ~{result['total_wall_hours']:.2f} h on {cores} "
              f"cores (aim <= 3 h on 2 cores)", flush=True)
    return result


if __name__ == "__main__":
    run()
