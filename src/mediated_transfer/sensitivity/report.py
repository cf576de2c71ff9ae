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
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..atomic import atomic_write_text
from ..metrics import median_time
from ..reporting.collect import CellRuns, collect_sweep
from ..reporting.figures import _pyplot
from ..reporting.formats import write_csv
from ..reporting.intervals import sem
from ..reporting.paper import paper_rows
from .measures import ArmGain, Measures, arm_gain
from ..env.scripted import random_success_rate
from .study import Study, World

REPORT = "SENSITIVITY.md"
READING_START = "<!-- reading: written by hand, kept when the report is rebuilt -->"
READING_END = "<!-- /reading -->"
PAPER_TABLE = "II"
"""The paper's table of the study's learner (linear Q(lambda) + RBF)."""


@dataclass
class WorldResult:
    world: World
    changes: str
    random_success: float
    runs: dict[str, int]
    """Finished runs per cell (failed ones not counted)."""
    failed: dict[str, int]
    discovery_median: float | None = None
    """Median learning step of the first rewarded target episode, without transfer."""
    learning_median: float | None = None
    """Median steps from that reward to the first <R> >= threshold, without transfer."""
    reward_loss_none: float | None = None
    reward_loss_none_sem: float | None = None
    gains: dict[str, ArmGain] = field(default_factory=dict)


def measure(study: Study, measures: Measures, progress=print) -> list[WorldResult]:
    cfg = study.config
    threshold, budget = float(cfg.threshold), int(cfg.scale.budget)
    rates = _random_rates(study, measures, progress)
    results = []
    for world in study.worlds:
        cells: dict[str, CellRuns] = collect_sweep(
            study.sweep_dir, str(cfg.algorithm.name), str(cfg.representation.name), budget,
            int(cfg.scale.eval_points), world.variant, int(cfg.scale.eval_episodes))
        cells = {name: c for name, c in cells.items() if name in study.cells}
        row = WorldResult(world, world.changes(study.baseline.config), rates[world.option],
                          {c: len(cells[c].results) if c in cells else 0 for c in study.cells},
                          {c: len(cells[c].failed) for c in study.cells if c in cells and cells[c].failed})
        none = cells.get("none_0")
        if none is not None and none.results:
            runs = none.results
            row.discovery_median = median_time([r.first_target_reward_step for r in runs])
            row.learning_median = median_time([r.learning_span(threshold) for r in runs])
            losses = np.array([r.reward_loss for r in runs])
            row.reward_loss_none = float(losses.mean())
            row.reward_loss_none_sem = sem(losses)
            for cell in study.transfer_cells:
                if cell in cells and cells[cell].results:
                    row.gains[cell] = arm_gain(cell, cells[cell].results, runs, threshold, budget, measures)
        results.append(row)
    return results


def paper_gains() -> dict[str, tuple[float, float | None]]:
    """The paper's gain of each transfer row of Table II over its row without transfer:
    (L_R ratio, time-to-threshold ratio or None)."""
    rows = {r.cell: r for r in paper_rows(PAPER_TABLE)}
    none = rows["none_0"]
    gains = {}
    for cell, row in rows.items():
        if cell == "none_0":
            continue
        time = (row.time_to_threshold / none.time_to_threshold
                if row.time_to_threshold and none.time_to_threshold else None)
        gains[cell] = (row.reward_loss_mean / none.reward_loss_mean, time)
    return gains


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


def plot(results: list[WorldResult], study: Study, path: Path) -> Path:
    """The gain (L_R ratio, time-to-threshold ratio; lower is a larger gain) of each transfer arm
    against discovery rarity (random policy's success rate) and post-discovery learning time,
    every world on one picture, the paper's gains as dashed lines."""
    plt = _pyplot()
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FuncFormatter, PercentFormatter

    paper = paper_gains()
    fig, axes = plt.subplots(2, 2, figsize=(12, 9), sharey="row")
    markers = {"regular": "o", "scaffolded": "s"}
    colors = plt.get_cmap("tab10")
    for row, (what, label) in enumerate([("reward_loss_ratio", "L_R ratio (transfer / none)"),
                                         ("threshold_time_ratio", "time-to-threshold ratio (transfer / none)")]):
        for col, (x_of, x_label, percent) in enumerate([
                (lambda r: r.random_success, "random policy's success rate on target tasks (discovery rarity)", True),
                (lambda r: r.learning_median, "median steps from first reward to <R> >= 8, without transfer", False)]):
            ax = axes[row, col]
            for k, r in enumerate(results):
                x = x_of(r)
                if x is None or not x > 0:
                    continue
                for cell, gain in r.gains.items():
                    interval = getattr(gain, what)
                    strategy = cell.split("_")[0]
                    # Scaffolded a little to the right, so both arms of a world stay visible.
                    shift = 1.0 if strategy == "regular" else 1.02
                    err = [[max(0.0, interval.value - interval.low)], [max(0.0, interval.high - interval.value)]]
                    ax.errorbar([x * shift], [interval.value], yerr=err, fmt=markers.get(strategy, "^"),
                                color=colors(k % 10), capsize=3, alpha=0.9,
                                mfc=colors(k % 10) if strategy == "regular" else "white")
            for cell, (loss, time) in paper.items():
                if cell in study.transfer_cells:
                    value = loss if row == 0 else time
                    if value is not None:
                        ax.axhline(value, ls="--", lw=1, color="0.4" if cell.startswith("regular") else "0.7")
                        ax.text(1.0, value, f" paper {cell}", transform=ax.get_yaxis_transform(),
                                fontsize=7, va="center", color="0.3")
            ax.axhline(1.0, lw=0.8, color="black")
            if percent:  # rates, on a linear axis (the worlds span a factor of about 4)
                ax.xaxis.set_major_formatter(PercentFormatter(1.0, decimals=2))
            else:
                ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v / 1000:.0f}k"))
            ax.set_xlabel(x_label, fontsize=9)
            if col == 0:
                ax.set_ylabel(label)
            ax.grid(alpha=0.3)

    handles = [Line2D([], [], ls="", marker="o", color=colors(k % 10), label=r.world.option)
               for k, r in enumerate(results)]
    handles += [Line2D([], [], ls="", marker=markers.get(c.split("_")[0], "^"), color="black",
                       mfc="black" if c.startswith("regular") else "white", label=c)
                for c in study.transfer_cells]
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8, frameon=False)
    for ax in axes.flat:
        ax.set_ylim(bottom=0)
    cfg = study.config
    fig.suptitle(f"Gain from transfer against the task (issue 13): linear Q(lambda) + RBF, "
                 f"{cfg.scale.budget:,} steps, {len(study.seeds)} seeds per arm\n"
                 f"filled: regular, open: scaffolded; bars: {int(100 * Measures().confidence)} % "
                 "bootstrap intervals; below 1 = transfer helps", fontsize=10)
    fig.tight_layout(rect=(0, 0.12, 1, 0.95))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


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


def write_report(study: Study, measures: Measures, reports_dir: Path, progress=print) -> list[Path]:
    results = measure(study, measures, progress)
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
    reading = _kept_reading(path)
    atomic_write_text(path, body + "\n\n## Reading\n\n" + reading + "\n")
    return [path, csv, figure]


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
