"""``python -m mediated_transfer.reporting.transfer_answer``: the registered answer to the paper's
open question, "does transfer help a learner other than Q-learning?", from a table sweep's stored
runs (Table V, SB3's PPO: ``conf/experiment/table5_ppo.yaml``, which fixed the measures and the
rule before its first run). This module applies that rule and nothing else:

- per transfer row, the ratio of mean L_R (row / none_0) with a 95 % percentile bootstrap
  interval over runs; **helps** when it lies entirely below 1, **hurts** when entirely above,
  **undecided** when it includes 1 (said with the point estimate's side): R1 of
  reporting/verdicts.py, the reproduction's own;
- per strategy, its best N_source (the lowest mean L_R) carries the strategy's answer; every
  row's outcome stands beside it, since that row was picked among five;
- overall, "transfer helps <learner>" when the best row of regular or scaffolded transfer holds;
  "transfer does not help <learner>" when no transfer row's interval lies below 1.

Beside the rule, as registered: the ratio of median per-run times to threshold, the runs that
never learn, and the discovery / learning split (the first rewarded target episode; from there to
the first <R> >= 8), medians with intervals, a run that never gets there counted as slower, with
each row's median source phase (discovery's steps include it).

Outside the rule, added after Table V's runs were in and deciding nothing: the ratio of median
L_R (does the typical run learn sooner, or only the slowest runs?) and every run's L_R drawn per
row, since a mean over runs that never learn (L_R near 250 each) can move without the median.
``--experiment table4_dnn`` applies the same rule to the DQN's table (not registered there:
a cross-check of the machinery on a learner the paper did study).
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from omegaconf import OmegaConf

from ..config.conf_dir import CONF_DIR
from ..metrics import MetricsConfig
from ..results import RunResult
from ..studies import Study, Written, added_in, command
from .collect import CellRuns, collect_sweep
from .figures import _pyplot
from .intervals import format_interval, median_interval, ratio_of_means, ratio_of_medians, sem
from .paper import scheme
from .reproduction.runs import never_learns
from .reproduction.wording import steps_k
from .verdicts import BELOW, HOLDS, OTHER_WAY, direction

EXPERIMENT = "table5_ppo"
REFERENCE = "none_0"
STRATEGIES = ("regular", "scaffolded")
LEARNERS = {"sb3_ppo": "PPO", "dqn": "the DQN", "linear_q": "linear Q(λ)"}
"""How the answer names a learner (its algorithm's name otherwise)."""


@dataclass(frozen=True)
class Registered:
    """What the experiment's file fixed: its rows (cells, in order) and runs per row."""

    experiment: str
    cells: list[str]
    runs_per_row: int
    file: Path

    @classmethod
    def read(cls, experiment: str, scale: str, conf_dir: Path = CONF_DIR) -> "Registered":
        file = conf_dir / "experiment" / f"{experiment}.yaml"
        if not file.is_file():
            known = sorted(p.stem for p in (conf_dir / "experiment").glob("table*.yaml"))
            raise ValueError(f"--experiment={experiment!r} is unknown; allowed: {', '.join(known)}")
        scale_file = conf_dir / "scale" / f"{scale}.yaml"
        if not scale_file.is_file():
            known = sorted(p.stem for p in (conf_dir / "scale").glob("*.yaml"))
            raise ValueError(f"--scale={scale!r} is unknown; allowed: {', '.join(known)}")
        cells = str(OmegaConf.load(file).hydra.sweeper.params.cell).split(",")
        return cls(experiment, [c.strip() for c in cells], int(OmegaConf.load(scale_file).seeds), file)


@dataclass(frozen=True)
class RowAnswer:
    """One transfer row's measures against none_0 and its outcome under R1."""

    cell: str
    strategy: str
    n_source: int
    runs: int
    loss_mean: float
    loss_sem: float
    loss_ratio: tuple[float, float, float]
    time_ratio: tuple[float, float, float]
    median_ratio: tuple[float, float, float]
    """Median L_R over none_0's, with its interval: outside the rule."""
    never_learn: int
    outcome: str
    """R1 on loss_ratio, the claim's side below 1."""

    @property
    def words(self) -> str:
        return outcome_words(self.outcome, self.loss_ratio[0])


@dataclass(frozen=True)
class SplitRow:
    """When a row's runs first solve a target task (discovery) and how long learning the pull
    then takes (learning): medians with intervals, never counted as slower."""

    cell: str
    runs: int
    discovered: int
    learned: int
    discovery: tuple[float, float, float]
    learning: tuple[float, float, float]
    source_phase: float | None
    """The median step at which the source phase ended (None without one): discovery counts it."""


@dataclass(frozen=True)
class Measures:
    registered: Registered
    learner: str
    reference: CellRuns | None
    rows: list[RowAnswer]
    best: dict[str, RowAnswer]
    splits: list[SplitRow]
    losses: dict[str, np.ndarray]
    """Every run's L_R per row, none_0 included, in the registered order."""
    finished: int
    failed: list[RunResult]


def outcome_words(outcome: str, point: float) -> str:
    """The registered words for one row's R1 outcome."""
    if outcome == HOLDS:
        return "transfer helps"
    if outcome == OTHER_WAY:
        return "transfer hurts"
    side = "below" if point < 1 else ("at" if point == 1 else "above")
    return f"undecided (point estimate {side} 1)"


def answer(best: dict[str, RowAnswer], rows: list[RowAnswer], learner: str) -> str:
    """The registered overall answer, never kinder than the rule."""
    if not rows:
        return "none yet: no transfer row has finished runs"
    helping = [s for s, row in best.items() if row.outcome == HOLDS]
    if helping:
        which = " and ".join(f"{scheme(s)} (best N_source = {best[s].n_source}, L_R ratio "
                             f"{format_interval(best[s].loss_ratio)})" for s in helping)
        return f"transfer helps {learner}: {which}"
    holding = [r.cell for r in rows if r.outcome == HOLDS]
    if not holding:
        return (f"transfer does not help {learner}: no transfer row's L_R ratio interval lies "
                "entirely below 1")
    return (f"not decided by the registered rule: {', '.join(holding)} hold{'s' if len(holding) == 1 else ''}, "
            "but no strategy's best row does")


def infinite_if_none(values: list[int | None]) -> np.ndarray:
    return np.array([math.inf if v is None else v for v in values], dtype=float)


def measure(registered: Registered, cells: dict[str, CellRuns]) -> Measures:
    reference = cells.get(REFERENCE)
    rows, splits, losses_by_cell = [], [], {}
    threshold = MetricsConfig().threshold
    compared = reference is not None and bool(reference.results)
    if compared:  # what every transfer row is compared with
        without = [r.reward_loss for r in reference.results]
        without_times = infinite_if_none([r.time_to_threshold for r in reference.results])
    for cell in registered.cells:
        runs = cells[cell].results if cell in cells else []
        if not runs:
            continue
        discovery = infinite_if_none([r.first_target_reward_step for r in runs])
        learning = infinite_if_none([r.learning_span(threshold) for r in runs])
        switches = [r.source_phase_end for r in runs if r.source_phase_end is not None]
        splits.append(SplitRow(cell, len(runs), int(np.isfinite(discovery).sum()), int(np.isfinite(learning).sum()),
                               median_interval(discovery), median_interval(learning),
                               float(np.median(switches)) if switches else None))
        losses = losses_by_cell[cell] = np.array([r.reward_loss for r in runs])
        if cell == REFERENCE or not compared:
            continue
        loss_ratio = ratio_of_means(losses, without)
        time_ratio = ratio_of_medians(infinite_if_none([r.time_to_threshold for r in runs]), without_times)
        rows.append(RowAnswer(cell=cell, strategy=cells[cell].strategy, n_source=cells[cell].n_source, runs=len(runs),
                              loss_mean=float(losses.mean()), loss_sem=sem(losses), loss_ratio=loss_ratio,
                              time_ratio=time_ratio, median_ratio=ratio_of_medians(losses, without),
                              never_learn=sum(map(never_learns, runs)), outcome=direction(loss_ratio, BELOW)))
    best = {}
    for strategy in STRATEGIES:
        own = [r for r in rows if r.strategy == strategy]
        if own:
            best[strategy] = min(own, key=lambda r: r.loss_mean)
    algorithm = next((r.algorithm for c in cells.values() for r in c.results), "")
    return Measures(registered, LEARNERS.get(algorithm, algorithm), reference, rows, best, splits, losses_by_cell,
                    sum(len(c.results) for c in cells.values()), [r for c in cells.values() for r in c.failed])


def plot(measures: Measures, path: Path) -> Path:
    """Left, the rule: each transfer row's L_R ratio with its interval, the line of no difference
    at 1. Right, outside it: every run's L_R per row, where a mean's move shows its runs."""
    plt = _pyplot()
    cells = list(measures.losses)  # one row per cell, none_0 first, on both panels
    at = {cell: i for i, cell in enumerate(cells)}
    fig, (ax, runs_ax) = plt.subplots(1, 2, sharey=True, figsize=(11.0, 0.38 * len(cells) + 1.6))
    colours = {HOLDS: "tab:green", OTHER_WAY: "tab:red"}
    for row in measures.rows:
        point, low, high = row.loss_ratio
        colour, i = colours.get(row.outcome, "tab:gray"), at[row.cell]
        ax.plot([low, min(high, 10.0)], [i, i], color=colour, lw=2)
        ax.plot([point], [i], "o", color=colour)
    ax.axvline(1.0, color="black", ls="--", lw=1)
    if REFERENCE in at:
        ax.text(1.0, at[REFERENCE], " the reference", va="center", fontsize=8)
    ax.set_yticks(range(len(cells)), cells)
    ax.invert_yaxis()
    ax.set_xlabel("L_R with transfer / without (95 % bootstrap interval); < 1: transfer helps")
    ax.set_title(f"Does transfer help {measures.learner}? ({measures.registered.experiment})", fontsize=10)
    jitter = np.random.default_rng(0)  # seeded: the same runs draw the same picture
    for cell, losses in measures.losses.items():
        i = at[cell]
        runs_ax.plot(losses, i + jitter.uniform(-0.18, 0.18, len(losses)), "o", ms=3.5, alpha=0.6,
                     color="tab:blue" if cell == REFERENCE else "tab:gray")
        runs_ax.plot([np.median(losses)] * 2, [i - 0.3, i + 0.3], color="black", lw=1.5)
    runs_ax.set_xlabel("L_R per run (bar: median); outside the rule")
    runs_ax.set_title("Every run", fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def render(measures: Measures, figure: str | None, scale: str) -> str:
    reg = measures.registered
    registered_here = reg.experiment == EXPERIMENT
    heading = "The registered answer" if registered_here else "Table V's rule as a cross-check"
    where = (f"the rule and measures were fixed in `conf/experiment/{reg.experiment}.yaml` (added in "
             f"{added_in(reg.file)}) before its first run" if registered_here else
             f"the rule and measures are those `conf/experiment/{EXPERIMENT}.yaml` registered for Table V, "
             f"applied to `{reg.experiment}`, for which they were not registered")
    lines = [f"# Does transfer help {measures.learner}? {heading} ({reg.experiment})", "",
             "Generated by `python -m mediated_transfer.reporting.transfer_answer "
             f"--experiment {reg.experiment} --scale {scale}` from the stored runs; {where}. "
             "Do not edit by hand.", ""]
    expected = len(reg.cells) * reg.runs_per_row
    if measures.reference is None or not measures.reference.results:
        return "\n".join(lines + [f"No runs without transfer ({REFERENCE}) yet: "
                                  f"`python -m mediated_transfer experiment={reg.experiment} scale={scale}`.", ""])
    if measures.finished < expected:
        lines += [f"**Incomplete:** {measures.finished} of {expected} runs; the answer below is provisional.", ""]
    if measures.failed:
        lines += ["Stopped as failed, in no row: " + ", ".join(
            f"{r.strategy}_{r.n_source} seed {r.seed} ({r.failure})" for r in measures.failed) + ".", ""]
    lines += [f"**Answer ({'the registered rule' if registered_here else 'cross-check'}):** {answer(measures.best, measures.rows, measures.learner)}.", ""]
    lines += ["Per strategy, its best N_source (lowest mean L_R) carries its answer; that row was picked "
              "among five, which its interval does not correct for, so every row's outcome stands below.", ""]
    for strategy, row in measures.best.items():
        lines.append(f"- {scheme(strategy)}: best N_source = {row.n_source}, L_R ratio "
                     f"{format_interval(row.loss_ratio)}: {row.words}.")
    ref = np.array([r.reward_loss for r in measures.reference.results])
    lines += ["", f"Without transfer: {len(ref)} runs, L_R {ref.mean():.1f} ± {sem(ref):.1f}, "
              f"{sum(map(never_learns, measures.reference.results))} never learn.", "",
              "| row | runs | L_R mean ± SEM | L_R ratio to none_0 [95 % CI] | median time-to-threshold ratio "
              "[95 % CI] | never learn | outcome |", "|---|---:|---:|---|---|---:|---|"]
    for row in measures.rows:
        lines.append(f"| {row.cell} | {row.runs} | {row.loss_mean:.1f} ± {row.loss_sem:.1f} | "
                     f"{format_interval(row.loss_ratio)} | {format_interval(row.time_ratio)} | "
                     f"{row.never_learn} | {row.words} |")
    if figure:
        lines += ["", f"![L_R ratio per transfer row with its interval; every run's L_R per row]({figure})"]
    lines += ["", "## Discovery and learning", "",
              "Discovery: the learning step of the first rewarded target-task episode. Learning: from there "
              "to the first evaluation point with <R> >= 8. Medians over runs with 95 % bootstrap intervals; "
              "a run that never gets there counts as slower than any that does ('never').", "",
              "Discovery counts the source phase's learning steps, whose median end is given.", "",
              "| row | runs | source phase ends | discover | discovery | learn | learning |",
              "|---|---:|---:|---:|---|---:|---|"]
    for split in measures.splits:
        phase = "-" if split.source_phase is None else phase_steps(split.source_phase)
        lines.append(f"| {split.cell} | {split.runs} | {phase} | {split.discovered} | {_steps(split.discovery)} | "
                     f"{split.learned} | {_steps(split.learning)} |")
    lines += ["", "## Outside the rule: the typical run", "",
              "Added after the runs were in; it decides nothing. The rule compares mean L_R, which runs that "
              "learn late or never (L_R up to 250) weigh heavily; the ratio of median L_R asks whether the "
              "typical run learns sooner. 95 % bootstrap intervals as above; every run's L_R is drawn on the "
              "right of the figure.", "",
              "| row | L_R median | L_R range over runs | median L_R ratio to none_0 [95 % CI] |",
              "|---|---:|---:|---|", f"| {REFERENCE} | {np.median(ref):.1f} | {_range(ref)} | - |"]
    for row in measures.rows:
        losses = measures.losses[row.cell]
        lines.append(f"| {row.cell} | {np.median(losses):.1f} | {_range(losses)} | {format_interval(row.median_ratio)} |")
    return "\n".join(lines + [""])


def _range(losses: np.ndarray) -> str:
    return f"{losses.min():.1f}-{losses.max():.1f}"


def phase_steps(steps: float) -> str:
    """A source phase's end: '33k', or the steps themselves below 1k (one source task, soon solved)."""
    return steps_k(steps) if steps >= 1000 else f"{steps:.0f}"


def _steps(interval: tuple[float, float, float]) -> str:
    point, low, high = interval
    return f"{steps_k(point)} [{steps_k(low)}, {steps_k(high)}]"


def study(argv: list[str]) -> Study:
    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.reporting.transfer_answer",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--experiment", default=EXPERIMENT, help="the table experiment (default: %(default)s)")
    parser.add_argument("--scale", default="paper", help="the sweep's scale (default: %(default)s)")
    parser.add_argument("--root", default=".", help="the checkout whose multirun/ holds the runs")
    parser.add_argument("--out", default=None,
                        help="where to write (default: <root>/reports/<experiment>_answer.md, a scale "
                             "other than paper under reports/<scale>/)")
    args = parser.parse_args(argv)
    registered = Registered.read(args.experiment, args.scale)
    root = Path(args.root)
    sweep = root / "multirun" / args.experiment / args.scale
    if not sweep.is_dir():
        raise FileNotFoundError(f"no runs of {args.experiment} at scale {args.scale} in {sweep}; run the sweep "
                                f"first: python -m mediated_transfer experiment={args.experiment} scale={args.scale}")
    reports = root / "reports" if args.scale == "paper" else root / "reports" / args.scale
    out = Path(args.out) if args.out else reports / f"{args.experiment}_answer.md"

    def report(measures: Measures) -> Written:
        out.parent.mkdir(parents=True, exist_ok=True)
        figure = plot(measures, out.with_suffix(".png")) if measures.rows else None
        return Written({out: render(measures, figure and figure.name, args.scale)}, [figure] if figure else [])

    return Study(f"{args.experiment} answer", str(registered.file), lambda: collect_sweep(sweep),
                 lambda cells: measure(registered, cells), report,
                 lambda cells: [r for c in cells.values() for r in (*c.results, *c.failed)])


main = command(study)

if __name__ == "__main__":
    sys.exit(main())
