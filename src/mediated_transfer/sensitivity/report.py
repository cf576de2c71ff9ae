"""reports/SENSITIVITY.md: the study's table, figure and findings, built from its runs.

Everything measured is computed here from result.json files; the paper's numbers come from
reporting/paper_tables.csv. The section between READING_START and READING_END is written by a
person after reading the results and is kept when the report is rebuilt.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd

from ..atomic import atomic_write_text
from ..metrics import median_time
from ..reporting.collect import CellRuns, collect_sweep
from ..reporting.formats import write_csv
from ..reporting.intervals import sem
from .figures import plot
from .measures import Measures, WorldResult, arm_gain, paper_gains
from ..env.scripted import random_success_rate
from ..studies import Written
from .study import Study, World

REPORT = "SENSITIVITY.md"
READING_START = "<!-- reading: written by hand, kept when the report is rebuilt -->"
READING_END = "<!-- /reading -->"


def collect(study: Study) -> dict[str, dict[str, CellRuns]]:
    """The study's runs: world -> arm -> its runs (arms of the study only)."""
    cfg = study.config
    runs = {}
    for world in study.worlds:
        cells: dict[str, CellRuns] = collect_sweep(
            study.sweep_dir, str(cfg.algorithm.name), str(cfg.representation.name), int(cfg.scale.budget),
            int(cfg.scale.eval_points), world.variant, int(cfg.scale.eval_episodes))
        runs[world.option] = {name: c for name, c in cells.items() if name in study.cells}
    return runs


def measure(study: Study, runs: dict[str, dict[str, CellRuns]], measures: Measures,
            progress=print) -> list[WorldResult]:
    cfg = study.config
    threshold, budget = float(cfg.threshold), int(cfg.scale.budget)
    rates = _random_rates(study, measures, progress)
    results = []
    for world in study.worlds:
        cells = runs[world.option]
        row = WorldResult(world, world.changes(study.baseline.config), rates[world.option],
                          {c: len(cells[c].results) if c in cells else 0 for c in study.cells},
                          {c: len(cells[c].failed) for c in study.cells if c in cells and cells[c].failed})
        none = cells.get("none_0")
        if none is not None and none.results:
            runs_none = none.results
            row.discovery_median = median_time([r.first_target_reward_step for r in runs_none])
            row.learning_median = median_time([r.learning_span(threshold) for r in runs_none])
            losses = np.array([r.reward_loss for r in runs_none])
            row.reward_loss_none = float(losses.mean())
            row.reward_loss_none_sem = sem(losses)
            for cell in study.transfer_cells:
                if cell in cells and cells[cell].results:
                    row.gains[cell] = arm_gain(cell, cells[cell].results, runs_none, threshold, budget, measures)
        results.append(row)
    return results


def table(results: list[WorldResult], study: Study) -> pd.DataFrame:
    records = []
    for r in results:
        record = {
            "world": r.world.option,
            "changes": r.changes,
            "random policy success": f"{100 * r.random_success:.3f} %",
            "runs": " / ".join(str(r.runs[c]) for c in study.cells)
                    + (f" ({sum(r.failed.values())} failed)" if r.failed else ""),
            "discovery (median step)": _steps(r.discovery_median),
            "learning after discovery (median)": _steps(r.learning_median),
            "L_R without transfer": "-" if r.reward_loss_none is None
                                    else f"{r.reward_loss_none:.1f} ± {r.reward_loss_none_sem:.1f}",
        }
        for cell in study.transfer_cells:
            g = r.gains.get(cell)
            record[f"{cell}: L_R ratio"] = "-" if g is None else _interval(g.reward_loss_ratio)
            record[f"{cell}: time ratio"] = "-" if g is None else (
                _interval(g.threshold_time_ratio) + ("" if g.threshold_reached else " (bound)"))
        records.append(record)
    return pd.DataFrame.from_records(records)


def findings(results: list[WorldResult], study: Study) -> list[str]:
    """Statements read off the measurements (no judgement): per transfer arm, the world with the
    largest gain, and which worlds' intervals reach the paper's gain."""
    lines = []
    paper = paper_gains()
    for cell in study.transfer_cells:
        measured = [(r, r.gains[cell]) for r in results if cell in r.gains]
        if not measured:
            continue
        best_r, best = min(measured, key=lambda m: m[1].reward_loss_ratio.value)
        loss, time = paper.get(cell, (None, None))
        lines.append(f"- **{cell}**: largest L_R gain in `{best_r.world.option}` "
                     f"(ratio {_interval(best.reward_loss_ratio)}); the paper's ratio is "
                     f"{_number(loss)}, time ratio {_number(time)}.")
        reach = [r.world.option for r, g in measured if loss is not None and g.reward_loss_ratio.low <= loss]
        lines.append(f"  Worlds whose L_R-ratio interval reaches the paper's: {', '.join(reach) or 'none'}.")
        reach_t = [r.world.option for r, g in measured if time is not None and g.threshold_time_ratio.low <= time]
        lines.append(f"  Worlds whose time-ratio interval reaches the paper's: {', '.join(reach_t) or 'none'}.")
    return lines


def report(study: Study, results: list[WorldResult], measures: Measures, reports_dir: Path) -> Written:
    """SENSITIVITY.md's text, its table and figure (written here)."""
    out = reports_dir / "sensitivity"
    out.mkdir(parents=True, exist_ok=True)
    frame = table(results, study)
    csv = write_csv(frame, out / "sensitivity.csv")
    figure = plot(results, study, out / "sensitivity.png")
    cfg = study.config
    missing = sum(len(study.seeds) - n for r in results for n in r.runs.values())
    overrides = f" and the overrides `{study.variant}`" if study.variant else ""
    header = [
        "# Sensitivity study: how much transfer helps depends on the task (issue 13)",
        f"Built by `python -m mediated_transfer.sensitivity` from the runs of the pre-registered study "
        f"`conf/experiment/sensitivity.yaml` (its git history shows it was committed before any of its "
        f"runs; no world was chosen after seeing results): {len(study.worlds)} worlds x "
        f"{len(study.cells)} arms x {len(study.seeds)} seeds, linear Q(lambda) + RBF with Table I's "
        f"values{overrides}, {cfg.scale.budget:,} learning steps, {cfg.scale.eval_points} x "
        f"{cfg.scale.eval_episodes} evaluation episodes (scale {cfg.scale.name})."
        + (f" **{missing} runs are not finished yet**; their rows count what exists." if missing else ""),
        "Columns: the random policy's success rate on target tasks "
        f"({measures.random_episodes:,} episodes; how rare discovery is); without transfer, the median "
        "learning step of the first rewarded target episode (discovery) and the median steps from it to "
        "the first <R> >= 8 (learning; '-' when most runs never get there); per transfer arm, the ratio "
        "of its mean L_R and of its mean curve's time to threshold to those without transfer, with "
        f"{int(100 * measures.confidence)} % bootstrap intervals over seeds (below 1: transfer helps; "
        "'bound': the arm's mean curve never stays above the threshold, so its time is the budget). "
        "Runs: finished runs per arm (" + ", ".join(study.cells) + ").",
    ]
    table_md = _markdown(frame)
    body = "\n\n".join([*header, table_md, f"![gain against the task](sensitivity/{figure.name})",
                        "## Findings (read off the table)", "\n".join(findings(results, study))])
    path = reports_dir / REPORT
    return Written({path: body + "\n\n## Reading\n\n" + _kept_reading(path) + "\n"}, [csv, figure])


def _kept_reading(path: Path) -> str:
    text = path.read_text() if path.is_file() else ""
    match = re.search(re.escape(READING_START) + r".*?" + re.escape(READING_END), text, flags=re.S)
    if match:
        return match.group(0)
    return f"{READING_START}\n(not written yet)\n{READING_END}"


def _random_rates(study: Study, measures: Measures, progress) -> dict[str, float]:
    """Each world's random-policy success rate, cached in the sweep folder by world and settings
    (about 10 s per world)."""
    cache = study.sweep_dir / "random_policy.json"
    known = json.loads(cache.read_text()) if cache.is_file() else {}
    rates = {}
    for world in study.worlds:
        key = hashlib.sha256(json.dumps([world.config.to_dict(), measures.random_episodes,
                                         measures.random_seed], sort_keys=True).encode()).hexdigest()[:16]
        if key not in known:
            progress(f"random policy on {world.option}: {measures.random_episodes:,} target episodes")
            known[key] = random_success_rate(world.config, measures.random_episodes, measures.random_seed)
            study.sweep_dir.mkdir(parents=True, exist_ok=True)
            atomic_write_text(cache, json.dumps(known, indent=1, sort_keys=True) + "\n")
        rates[world.option] = known[key]
    return rates


def _markdown(frame: pd.DataFrame) -> str:
    rows = ["| " + " | ".join(frame.columns) + " |", "|" + "|".join("---" for _ in frame.columns) + "|"]
    rows += ["| " + " | ".join(str(v) for v in record) + " |" for record in frame.itertuples(index=False)]
    return "\n".join(rows)


def _interval(i) -> str:
    if math.isnan(i.low):
        return f"{i.value:.2f}"
    return f"{i.value:.2f} [{i.low:.2f}, {i.high:.2f}]"


def _steps(value: float | None) -> str:
    return "never" if value is None else f"{value:,.0f}"


def _number(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"
