"""Tables II-IV from run outputs: each row as in the paper (scheme, N_source, L_R mean +/- SEM,
time to threshold), the paper's values beside it, the number of runs and the scale stated.

One pandas DataFrame of texts per table is written as Markdown and LaTeX, one of numbers as CSV
(formats.py). The measured time to threshold is that of the mean curve, as in the paper; the
median of the per-run values and how many runs reach the threshold stand next to it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from .formats import LATEX, MARKDOWN, Markup, write_csv, write_latex, write_markdown
from .paper import PaperRow, scheme


@dataclass(frozen=True)
class TableRow:
    strategy: str
    n_source: int
    summary: dict | None
    """metrics.summarise_runs of the cell's runs; None when none has finished."""
    paper: PaperRow | None
    """The paper's row; None for a cell the paper does not have."""
    expected_runs: int
    failed: int = 0
    """Runs stopped as failed (a diverged learner): not in the summary, counted here."""

    @property
    def cell(self) -> str:
        return f"{self.strategy}_{self.n_source}"

    @property
    def n_runs(self) -> int:
        return 0 if self.summary is None else int(self.summary["n_runs"])


@dataclass(frozen=True)
class TableHeader:
    title: str
    scale: str
    budget: int
    eval_points: int
    eval_episodes: int
    runs_per_row: int
    threshold: float
    max_reward: float
    variant: str = ""
    """The overrides of this sweep (Hydra's override_dirname); '' for the baseline."""
    stale_runs: int = 0
    """Runs computed by other code than the current (provenance.py); said in the header."""
    left_out_runs: int = 0
    """Damaged runs left out of the table (reporting.collect); said in the header."""

    def heading(self, m: Markup) -> str:
        title = m.text(self.title)
        return f"{title}, variant {m.code(self.variant)}" if self.variant else title

    def describe(self, m: Markup) -> str:
        text = (f"Scale {m.code(self.scale)}: {self.budget:,} learning steps per run; {m.reward} at "
                f"{self.eval_points} evaluation points x {self.eval_episodes} target-task episodes; "
                f"{self.runs_per_row} runs (seeds) per row. {m.reward_loss} sums {m.max_reward} - "
                f"{m.reward} over the {self.eval_points} points (0 to {self.eval_points * self.max_reward:g}).")
        if self.variant:
            text += (f" Variant {m.code(self.variant)}: the experiment's config with these overrides; "
                     "only the runs of this variant.")
        if self.stale_runs:
            text += (f" {self.stale_runs} of the runs were computed by other code than the current "
                     f"(stale; rerun the sweep with rerun_stale=true to recompute them).")
        if self.left_out_runs:
            text += (f" {self.left_out_runs} damaged run{'s were' if self.left_out_runs > 1 else ' was'} "
                     "left out (the report command names them; rerunning the sweep sets them aside "
                     "and computes them again).")
        if self.scale != "paper":
            text += (" This is not the paper's scale (500,000 steps, 25 x 100, 20 runs): the "
                     "numbers are not comparable with the paper's.")
        return text

    def threshold_note(self, m: Markup) -> str:
        success = m.text(f"{self.threshold / self.max_reward:.0%}")
        return (f"Time to threshold: learning steps until the mean curve over runs stays at "
                f"{m.reward} {m.geq} {self.threshold:g} ({success} success) to the end; '-': never. "
                f"Per-run median: the same per run (a run that never reaches it counts as slowest), "
                f"with the number of runs that reach it.")


def table_rows(summaries: dict[str, dict], strategies: dict[str, tuple[str, int]],
               paper: list[PaperRow], expected_runs: int,
               failed: dict[str, int] | None = None) -> list[TableRow]:
    """The paper's rows in its order, then any measured cell the paper does not have.

    ``summaries``: cell -> summary; ``strategies``: cell -> (strategy, n_source) of measured
    cells; ``failed``: cell -> runs stopped as failed.
    """
    failed = failed or {}
    rows = [TableRow(p.strategy, p.n_source, summaries.get(p.cell), p, expected_runs, failed.get(p.cell, 0))
            for p in paper]
    known = {p.cell for p in paper}
    extra = sorted((c for c in strategies if c not in known and (c in summaries or c in failed)),
                   key=lambda c: strategies[c])
    rows += [TableRow(*strategies[c], summaries.get(c), None, expected_runs, failed.get(c, 0)) for c in extra]
    return rows


def write_tables(rows: list[TableRow], header: TableHeader, out_dir: str | Path, name: str) -> list[Path]:
    """``<out_dir>/<name>.md``, ``.csv`` and ``.tex``; returns the three paths."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    preamble = [header.heading(MARKDOWN), header.describe(MARKDOWN), header.threshold_note(MARKDOWN)]
    caption = " ".join([f"{header.heading(LATEX)}.", header.describe(LATEX), header.threshold_note(LATEX)])
    md, tex = shown(rows, MARKDOWN), shown(rows, LATEX)
    right = len(md.columns) - 1
    return [
        write_markdown(md, out_dir / f"{name}.md", preamble, ["left"] + ["right"] * right),
        write_csv(numbers(rows, header), out_dir / f"{name}.csv"),
        write_latex(tex, out_dir / f"{name}.tex", "l" + "r" * right, caption),
    ]


def shown(rows: list[TableRow], m: Markup) -> pd.DataFrame:
    """The table as read: one text per cell, headed as in the paper; without the paper's
    columns when the paper has no such table (Table V)."""
    heads = ["Scheme", m.n_source, "Runs", m.reward_loss,
             "Time to threshold", "Per-run median (reached)", f"{m.reward_loss} (paper)",
             "Time to threshold (paper)"]
    frame = pd.DataFrame([_texts(r, m) for r in rows], columns=heads)
    return frame if any(r.paper for r in rows) else frame.drop(columns=heads[-2:])


def _texts(row: TableRow, m: Markup) -> list[str]:
    s, p = row.summary, row.paper
    nothing = "all failed" if row.failed else "not run"
    measured = [nothing, "", ""] if s is None else [
        reward_loss_text(s["reward_loss_mean"], s["reward_loss_sem"], m),
        steps_text(s["time_to_threshold"]),
        f"{steps_text(s['time_to_threshold_median'])} ({s['runs_reaching_threshold']}/{s['n_runs']})",
    ]
    published = ["", ""] if p is None else [
        f"{p.reward_loss_mean:g} {m.pm} {p.reward_loss_sem:.2f}",
        "-" if p.time_to_threshold is None else f"{m.approx}{p.time_to_threshold:,}",
    ]
    runs = f"{row.n_runs}/{row.expected_runs}" + (f" ({row.failed} failed)" if row.failed else "")
    return [scheme(row.strategy), str(row.n_source), runs,
            *measured, *published]


def numbers(rows: list[TableRow], header: TableHeader) -> pd.DataFrame:
    """The table as processed: one number per cell (empty: not run, or never reached)."""
    records = []
    for r in rows:
        s, p = r.summary or {}, r.paper
        records.append({
            "scheme": scheme(r.strategy), "strategy": r.strategy, "n_source": r.n_source,
            "scale": header.scale, "variant": header.variant, "budget": header.budget,
            "eval_points": header.eval_points, "eval_episodes": header.eval_episodes,
            "runs": r.n_runs, "expected_runs": r.expected_runs, "failed_runs": r.failed,
            "reward_loss_mean": s.get("reward_loss_mean"), "reward_loss_sem": s.get("reward_loss_sem"),
            "time_to_threshold": s.get("time_to_threshold"),
            "time_to_threshold_median": s.get("time_to_threshold_median"),
            "runs_reaching_threshold": s.get("runs_reaching_threshold"),
            "final_reward_mean": s.get("final_reward_mean"),
            "paper_reward_loss_mean": p and p.reward_loss_mean, "paper_reward_loss_sem": p and p.reward_loss_sem,
            "paper_time_to_threshold": p and p.time_to_threshold,
        })
    frame = pd.DataFrame.from_records(records)
    # Learning steps and counts are integers; nullable, so that "never" and "not run" stay empty.
    counts = ["time_to_threshold", "runs_reaching_threshold", "paper_time_to_threshold"]
    return frame.astype({c: "Int64" for c in counts}).astype({c: "Float64" for c in (
        "reward_loss_mean", "reward_loss_sem", "time_to_threshold_median", "final_reward_mean",
        "paper_reward_loss_mean", "paper_reward_loss_sem")})


def reward_loss_text(mean: float, sem: float, m: Markup) -> str:
    return f"{mean:.2f} {m.pm} {'n/a' if math.isnan(sem) else f'{sem:.2f}'}"


def steps_text(value) -> str:
    return "-" if value is None else f"{int(round(value)):,}"
