"""Progress lines: where a single run is, and how far a sweep has come and how long it has left."""

from __future__ import annotations

import hashlib
import json
import logging
import math
import time
from pathlib import Path
from typing import TYPE_CHECKING

from ..atomic import atomic_write_text

if TYPE_CHECKING:
    from collections.abc import Sequence

    from ..results import RunResult
    from ..run import RunSpec

log = logging.getLogger("mediated_transfer")

PLAN_PREFIX = ".sweep_plan."
"""Plans are written into the sweep folder before the jobs start: which runs a launch has."""


def write_plan(sweep_dir: Path, runs: list[str], recompute: Sequence[str] = ()) -> Path:
    """The plan of one launch into one sweep folder: its runs' folders, those of them whose
    stale results it recomputes (their old result files do not count as finished), and when
    it started. Named after its runs, so sweeps that share the folder (a baseline and a
    variant) keep their own plans."""
    sweep_dir.mkdir(parents=True, exist_ok=True)
    name = hashlib.sha256("\n".join(runs).encode()).hexdigest()[:12]
    path = sweep_dir / f"{PLAN_PREFIX}{name}.json"
    plan = {"total": len(runs), "started": time.time(), "runs": runs, "recompute": list(recompute)}
    atomic_write_text(path, json.dumps(plan) + "\n")
    return path


class SingleRunProgress:
    """Progress of a single run, as execute_run's callbacks: ``<run>: step k/n, steps/s,
    <R> of the latest evaluation point, ~time left``."""

    def __init__(self, spec: "RunSpec"):
        self.spec, self.started = spec, time.perf_counter()
        self.latest: tuple[int, float, float] | None = None

    def evaluated(self, step: int, mean_reward: float, success_rate: float) -> None:
        self.latest = step, mean_reward, success_rate

    def __call__(self, step: int, budget: int) -> None:
        elapsed = time.perf_counter() - self.started
        left = elapsed * (budget - step) / step if step else math.nan
        reward = "" if self.latest is None else (
            f", <R> {self.latest[1]:.2f} ({self.latest[2]:.0%} solved) at step {self.latest[0]}")
        log.info("%s: step %d/%d, %.0f steps/s%s, ~%s left", self.spec.describe(), step, budget,
                 step / elapsed if elapsed > 0 else math.nan, reward, duration(left))


def run_line(label: str, result: "RunResult", status: str, sweep_name: str, sweep_dir: Path | None,
             run: str = "", stale: str | None = None) -> str:
    """``[sweep k/n, ~time left] <label>: L_R=..., steps/s`` for a finished (or found) run;
    ``run`` is its folder below ``sweep_dir``."""
    if status == "exists":
        what = "found, skipped" if stale is None else f"found, STALE ({stale}; rerun_stale=true recomputes it)"
    else:
        what = f"{result.learning_steps_per_s:,.0f} steps/s"
    outcome = f"FAILED ({result.failure})" if result.failed else f"L_R={result.reward_loss:.2f}"
    line = f"{label}: {outcome}, {what}"
    if sweep_dir is None:
        return line
    count = sweep_progress(sweep_dir, run)
    if count is None:
        return f"[{sweep_name}] {line}"
    finished, total, left = count
    eta = "" if left is None else f", ~{duration(left)} left"
    return f"[{sweep_name} {finished}/{total}{eta}] {line}"


def sweep_progress(sweep_dir: Path, run: str) -> tuple[int, int, float | None] | None:
    """(finished runs, runs of the launch, estimated seconds left), from the newest plan in
    ``sweep_dir`` that lists ``run`` and the result files of its runs; None without one."""
    plans = []
    for path in sweep_dir.glob(f"{PLAN_PREFIX}*.json"):
        try:
            plan = json.loads(path.read_text())
        except (OSError, ValueError):
            continue
        if run in plan.get("runs", []):
            plans.append(plan)
    if not plans:
        return None
    plan = max(plans, key=lambda p: p["started"])
    # Only this launch's runs: other sweeps (a variant) may share the folder.
    files = {r: sweep_dir / r / "result.json" for r in plan["runs"]}
    results = {r: f.stat().st_mtime for r, f in files.items() if f.is_file()}
    # A stale result the launch recomputes is finished only once rewritten.
    recompute = set(plan.get("recompute", []))
    finished = min(sum(r not in recompute or t >= plan["started"] for r, t in results.items()),
                   plan["total"])
    results = list(results.values())
    # Only runs computed since this launch tell the current speed (earlier ones were skipped).
    computed = sum(t >= plan["started"] for t in results)
    elapsed = time.time() - plan["started"]
    left = (plan["total"] - finished) * elapsed / computed if computed else None
    return finished, plan["total"], left


def duration(seconds: float | None) -> str:
    if seconds is None or not math.isfinite(seconds):
        return "?"
    seconds = int(round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}h{minutes:02d}m" if hours else f"{minutes}m{secs:02d}s"
