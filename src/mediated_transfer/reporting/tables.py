"""Tables II-IV from run outputs: each row as in the paper (scheme, N_source, L_R mean +/- SEM,
time to threshold), the paper's values beside it, the number of runs and the scale stated.

Written as Markdown (to read), CSV (to process) and LaTeX (booktabs, to typeset). The measured
time to threshold is that of the mean curve, as in the paper; the median of the per-run values
and how many runs reach the threshold stand next to it.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

from .paper import SCHEMES, PaperRow


@dataclass(frozen=True)
class TableRow:
    strategy: str
    n_source: int
    summary: dict | None
    """metrics.summarise_runs of the cell's runs; None when none has finished."""
    paper: PaperRow | None
    """The paper's row; None for a cell the paper does not have."""
    expected_runs: int

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

    def describe(self) -> str:
        text = (f"Scale `{self.scale}`: {self.budget:,} learning steps per run; <R> at "
                f"{self.eval_points} evaluation points x {self.eval_episodes} target-task episodes; "
                f"{self.runs_per_row} runs (seeds) per row. L_R sums R_max - <R> over the "
                f"{self.eval_points} points (0 to {self.eval_points * self.max_reward:g}).")
        if self.scale != "paper":
            text += (" This is not the paper's scale (500,000 steps, 25 x 100, 20 runs): the "
                     "numbers are not comparable with the paper's.")
        return text


def table_rows(summaries: dict[str, dict], strategies: dict[str, tuple[str, int]],
               paper: list[PaperRow], expected_runs: int) -> list[TableRow]:
    """The paper's rows in its order, then any measured cell the paper does not have.

    ``summaries``: cell -> summary; ``strategies``: cell -> (strategy, n_source) of measured cells.
    """
    rows = [TableRow(p.strategy, p.n_source, summaries.get(p.cell), p, expected_runs) for p in paper]
    known = {p.cell for p in paper}
    extra = sorted((c for c in summaries if c not in known), key=lambda c: strategies[c])
    rows += [TableRow(*strategies[c], summaries[c], None, expected_runs) for c in extra]
    return rows


def write_tables(rows: list[TableRow], header: TableHeader, out_dir: str | Path, name: str) -> list[Path]:
    """``<out_dir>/<name>.md``, ``.csv`` and ``.tex``; returns the three paths."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    files = {
        out_dir / f"{name}.md": markdown(rows, header),
        out_dir / f"{name}.csv": csv_text(rows, header),
        out_dir / f"{name}.tex": latex(rows, header),
    }
    for path, text in files.items():
        path.write_text(text)
    return list(files)


# --- formats -----------------------------------------------------------------------------------

COLUMNS = ["Scheme", "N_source", "Runs", "L_R", "Time to threshold", "Per-run median (reached)",
           "L_R (paper)", "Time to threshold (paper)"]


def _cells(row: TableRow, approx: str, pm: str) -> list[str]:
    s, p = row.summary, row.paper
    measured = ["not run", "", ""] if s is None else [
        _loss(s["reward_loss_mean"], s["reward_loss_sem"], pm),
        _steps(s["time_to_threshold"]),
        f"{_steps(s['time_to_threshold_median'])} ({s['runs_reaching_threshold']}/{s['n_runs']})",
    ]
    published = ["", ""] if p is None else [
        f"{p.reward_loss_mean:g} {pm} {p.reward_loss_sem:.2f}",
        "-" if p.time_to_threshold is None else f"{approx}{p.time_to_threshold:,}",
    ]
    return [SCHEMES[row.strategy], str(row.n_source), f"{row.n_runs}/{row.expected_runs}",
            *measured, *published]


def markdown(rows: list[TableRow], header: TableHeader) -> str:
    lines = [f"# {header.title}", "", header.describe(), "",
             _threshold_note(header), "",
             "| " + " | ".join(COLUMNS) + " |",
             "|" + "|".join(["---", "---:", "---:", "---:", "---:", "---:", "---:", "---:"]) + "|"]
    lines += ["| " + " | ".join(_cells(r, "~", "±")) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def csv_text(rows: list[TableRow], header: TableHeader) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow([
        "scheme", "strategy", "n_source", "scale", "budget", "eval_points", "eval_episodes",
        "runs", "expected_runs", "reward_loss_mean", "reward_loss_sem", "time_to_threshold",
        "time_to_threshold_median", "runs_reaching_threshold", "final_reward_mean",
        "paper_reward_loss_mean", "paper_reward_loss_sem", "paper_time_to_threshold",
    ])
    for r in rows:
        s, p = r.summary or {}, r.paper
        writer.writerow([
            SCHEMES[r.strategy], r.strategy, r.n_source, header.scale, header.budget,
            header.eval_points, header.eval_episodes, r.n_runs, r.expected_runs,
            _num(s.get("reward_loss_mean")), _num(s.get("reward_loss_sem")),
            _num(s.get("time_to_threshold")), _num(s.get("time_to_threshold_median")),
            _num(s.get("runs_reaching_threshold")), _num(s.get("final_reward_mean")),
            _num(p and p.reward_loss_mean), _num(p and p.reward_loss_sem),
            _num(p and p.time_to_threshold),
        ])
    return out.getvalue()


def latex(rows: list[TableRow], header: TableHeader) -> str:
    heads = ["Scheme", r"$N_\mathrm{source}$", "Runs", r"$\mathcal{L}_R$", "Time to threshold",
             "Per-run median (reached)", r"$\mathcal{L}_R$ (paper)", "Time to threshold (paper)"]
    body = [" & ".join(_tex(c) for c in _cells(r, "\x02", "\x01")) + r" \\" for r in rows]
    caption = _tex(f"{header.title}. {header.describe()} {_threshold_note(header)}")
    return "\n".join([
        r"% Generated by python -m mediated_transfer.reporting; needs \usepackage{booktabs}.",
        r"\begin{table}[t]", r"\centering", r"\small",
        r"\begin{tabular}{lrrrrrrr}", r"\toprule", " & ".join(heads) + r" \\", r"\midrule",
        *body, r"\bottomrule", r"\end{tabular}", rf"\caption{{{caption}}}", r"\end{table}", "",
    ])


def _threshold_note(header: TableHeader) -> str:
    return (f"Time to threshold: learning steps until the mean curve over runs stays at "
            f"<R> >= {header.threshold:g} ({header.threshold / header.max_reward:.0%} success) to the "
            f"end; '-': never. Per-run median: the same per run (a run that never reaches it "
            f"counts as slowest), with the number of runs that reach it.")


def _loss(mean: float, sem: float, pm: str) -> str:
    return f"{mean:.2f} {pm} {'n/a' if math.isnan(sem) else f'{sem:.2f}'}"


def _steps(value) -> str:
    return "-" if value is None else f"{int(round(value)):,}"


def _num(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    return f"{value:g}" if isinstance(value, float) else str(value)


def _tex(text: str) -> str:
    for raw, escaped in (("\\", r"\textbackslash{}"), ("&", r"\&"), ("%", r"\%"), ("_", r"\_"),
                         ("#", r"\#"), ("<R>", r"$\langle R\rangle$"), (">=", r"$\geq$"),
                         ("`", ""), ("\x01", r"$\pm$"), ("\x02", r"$\approx$ ")):
        text = text.replace(raw, escaped)
    return text
