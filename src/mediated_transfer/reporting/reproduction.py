"""``python -m mediated_transfer.reporting.reproduction``: reports/REPRODUCTION.md, a verdict on
each of the paper's six headline claims (shared NOTES.md), from the committed paper-scale runs
of Tables II-IV. Nothing in it is typed: every number comes from the runs' result.json files,
the paper's from paper_tables.csv.

Per claim: the paper's number beside ours; ratios (transfer row / reference row) of L_R and of
the per-run time to threshold with 95 % bootstrap intervals over runs; a verdict by a rule
declared here, before the numbers (``VERDICT_RULES``): reproduced, partly, not reproduced, or
undecided when 20 seeds cannot tell (with the seeds a decision would need). Per cell: IQM,
probability of improvement over the row without transfer, and runs that never learn (no
evaluation point at <R> >= 8) counted apart from the mean. Per learner: where a run's time goes,
discovery (first rewarded target episode), learning (discovery to first <R> >= 8), holding (L_R
lost after that point).
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..metrics import MetricsConfig, first_point_at_threshold, learning_span
from .collect import CellRuns, collect_sweep
from .intervals import (bootstrap, format_interval, iqm, median, probability_of_improvement, ratio_of_means,
                        ratio_of_medians, sem, seeds_to_decide)
from .paper import paper_rows

TABLES = {"II": ("table2_rbf", "RBF"), "III": ("table3_fsr", "FSR"), "IV": ("table4_dnn", "DNN")}
BUDGET = 500_000
THRESHOLD = MetricsConfig().threshold
MAX_REWARD = MetricsConfig().max_reward
EXPECTED_RUNS = 20

VERDICT_RULES = """\
- **Ratio** = transfer row / reference row, of mean L_R or of the median per-run time to
  threshold (a run that never reaches it counts as slower than any that does). Intervals are
  95 % percentile bootstraps over runs (10,000 resamples, seeded).
- A difference **holds** when its interval excludes 1; it is **undecided** when the point
  estimate points the paper's way but the interval includes 1.
- **Reproduced**: every part of the claim holds, and where the paper gives a factor, our
  interval includes it or lies beyond it.
- **Partly**: the claim's direction holds but a part fails (e.g. a smaller factor than the
  paper's, or a row the paper says is not learned is learned).
- **Not reproduced**: the difference holds the other way, or is absent (interval includes 1
  with the point estimate against the claim).
- **Undecided**: the runs cannot tell; the seeds a decision would need are given.
- A claim over several rows takes each row's verdict by these rules, then: reproduced when every
  row is; not reproduced when a row holds the other way; partly when some row holds the
  claim's way; undecided when no row decides; not reproduced when every row shows no difference."""


@dataclass
class Learner:
    table: str
    name: str
    cells: dict[str, CellRuns]
    paper: dict

    def runs(self, cell: str) -> list:
        return self.cells[cell].results if cell in self.cells else []

    def losses(self, cell: str) -> np.ndarray:
        return np.array([r.reward_loss for r in self.runs(cell)])

    def times(self, cell: str) -> np.ndarray:
        """Per-run time to threshold, +inf for a run that never reaches it."""
        return np.array([math.inf if r.time_to_threshold is None else r.time_to_threshold
                         for r in self.runs(cell)], dtype=float)

    def never_learn(self, cell: str) -> int:
        return sum(map(never_learns, self.runs(cell)))

    def mean_curve_time(self, cell: str) -> int | None:
        return self.cells[cell].summary(MetricsConfig())["time_to_threshold"]


def never_learns(run) -> bool:
    """No evaluation point of the run reaches <R> >= 8."""
    return first_point_at_threshold(run.mean_reward, THRESHOLD) is None


NEVER_LEARN_COLUMNS = ("| seed | L_R | first rewarded target episode | final <R> | episodes | final TD loss |",
                       "|---:|---:|---|---:|---:|---:|")


def never_learn_row(run) -> str:
    """A run that never learns, as a row under NEVER_LEARN_COLUMNS: when it first found the
    reward, and the learner's state at the end (episodes run, last TD loss)."""
    s = run.learner_stats
    return (f"| {run.seed} | {run.reward_loss:.1f} | {_steps(run.first_target_reward_step)} | "
            f"{run.mean_reward[-1]:.2f} | {s.get('episodes', math.nan):,.0f} | {s.get('last_loss', math.nan):.1e} |")


def load(root: Path) -> dict[str, Learner]:
    learners = {}
    for table, (experiment, name) in TABLES.items():
        sweep = root / "multirun" / experiment / "paper"
        cells = collect_sweep(sweep, budget=BUDGET) if sweep.is_dir() else {}
        learners[table] = Learner(table, name, cells, {r.cell: r for r in paper_rows(table)})
    return learners


# --- formatting -------------------------------------------------------------------------------
def _steps(value: float | None) -> str:
    if value is None or math.isinf(value):
        return "never"
    return f"{value / 1000:.0f}k"


def _paper_time(p) -> float:
    return math.inf if p.time_to_threshold is None else p.time_to_threshold


# --- the claims ---------------------------------------------------------------------------------
def claim_1(L: dict[str, Learner]) -> tuple[str, list[str]]:
    rbf = L["II"]
    lines, verdicts = [], []
    base = rbf.paper["none_0"]
    for cell in ("regular_50", "scaffolded_50", "scaffolded_100"):
        ours = ratio_of_medians(rbf.times(cell), rbf.times("none_0"))
        paper = _paper_time(rbf.paper[cell]) / _paper_time(base)
        lines.append(f"| {cell} / none_0 | {_steps(_paper_time(rbf.paper[cell]))} / {_steps(_paper_time(base))} = "
                     f"{paper:.2f} | {_steps(rbf.mean_curve_time(cell))} / {_steps(rbf.mean_curve_time('none_0'))} | "
                     f"{_steps(np.median(rbf.times(cell)))} / {_steps(np.median(rbf.times('none_0')))} | {format_interval(ours)} |")
        verdicts.append(row_verdict(ours, paper))
        lines[-1] += f" {verdicts[-1]} |"
    head = ("| ratio of time to threshold | paper | ours, mean curve | ours, median per run | ours, ratio of "
            "medians [95 % CI] | row |\n|---|---|---|---|---|---|")
    return combine(verdicts), [head, *lines]


def claim_2(L: dict[str, Learner]) -> tuple[str, list[str]]:
    lines, holds = [], []
    for table in ("II", "III", "IV"):
        lr = L[table]
        for cell in ("regular_1", "scaffolded_1"):
            if not lr.runs(cell) or not lr.runs("none_0"):
                continue
            ours = ratio_of_means(lr.losses(cell), lr.losses("none_0"))
            p = lr.paper[cell].reward_loss_mean / lr.paper["none_0"].reward_loss_mean
            holds.append(row_verdict(ours))
            lines.append(f"| {lr.name} | {cell} / none_0 | {p:.2f} | {format_interval(ours)} | "
                         f"{probability_of_improvement(lr.losses(cell), lr.losses('none_0')):.2f} | {holds[-1]} |")
    head = ("| learner | ratio of mean L_R | paper | ours [95 % CI] | P(a run of the row beats one "
            "without transfer) | row |\n|---|---|---|---|---|---|")
    return combine(holds), [head, *lines]


def claim_3(L: dict[str, Learner]) -> tuple[str, list[str]]:
    lines, worse, unlearned = [], [], []
    for table in ("II", "III", "IV"):
        lr = L[table]
        for strategy in ("regular", "scaffolded"):
            cell, best = f"{strategy}_5000", f"{strategy}_50"
            if not lr.runs(cell) or not lr.runs(best):
                continue
            ours = ratio_of_means(lr.losses(cell), lr.losses(best))
            p = lr.paper[cell].reward_loss_mean / lr.paper[best].reward_loss_mean
            worse.append(row_verdict(ours, below=False))
            n, never = len(lr.runs(cell)), lr.never_learn(cell)
            paper_unlearned = lr.paper[cell].reward_loss_mean > 200  # the paper: "not learned at all"
            if paper_unlearned:
                unlearned.append(never > n / 2)
            lines.append(f"| {lr.name} | {cell} / {best} | {p:.2f} ({lr.paper[cell].reward_loss_mean:.0f}) | "
                         f"{format_interval(ours)} ({lr.losses(cell).mean():.1f}) | {never} of {n} |"
                         f" {'yes' if paper_unlearned else 'no'} | {worse[-1]} |")
    # "Not learned at all" is a second part: where the paper says so, most of our runs must not learn.
    verdict = combine(worse + ["reproduced" if u else "absent" for u in unlearned])
    head = ("| learner | ratio of mean L_R | paper (its L_R) | ours [95 % CI] (our L_R) | runs that "
            "never learn | paper: not learned at all | row (worse L_R) |\n|---|---|---|---|---|---|---|")
    return verdict, [head, *lines]


def claim_4(L: dict[str, Learner]) -> tuple[str, list[str]]:
    lines, verdicts = [], []
    for table in ("II", "III"):
        lr = L[table]
        for n in (15, 50, 100):
            reg, sca = f"regular_{n}", f"scaffolded_{n}"
            ours = ratio_of_medians(lr.times(sca), lr.times(reg))
            p = _paper_time(lr.paper[sca]) / _paper_time(lr.paper[reg])
            verdicts.append(row_verdict(ours))
            lines.append(f"| {lr.name} | N={n} | {_steps(_paper_time(lr.paper[sca]))} / "
                         f"{_steps(_paper_time(lr.paper[reg]))} = {p:.2f} | {_steps(np.median(lr.times(sca)))} / "
                         f"{_steps(np.median(lr.times(reg)))} | {format_interval(ours)} | {verdicts[-1]} |")
    head = ("| learner | N_source | paper: scaffolded / regular | ours, median per run | ours, ratio of "
            "medians [95 % CI] | row |\n|---|---|---|---|---|---|")
    return combine(verdicts), [head, *lines]


def claim_5(L: dict[str, Learner]) -> tuple[str, list[str]]:
    dnn = L["IV"]
    if not dnn.runs("none_0") or not dnn.runs("regular_100"):
        return "undecided", ["Table IV has no runs of these rows yet."]
    rows = []
    for cell, paper_final in (("none_0", "~5"), ("regular_100", "~9")):
        s = dnn.cells[cell].summary(MetricsConfig())
        n = s["n_runs"]
        rows.append(f"| {cell} | {_steps(_paper_time(dnn.paper[cell]))} | {paper_final} | "
                    f"{_steps(s['time_to_threshold'])} | {s['final_reward_mean']:.2f} ± {s['final_reward_sem']:.2f} | "
                    f"{s['runs_reaching_threshold']} of {n} | {dnn.never_learn(cell)} of {n} |")
    none_reaches = dnn.mean_curve_time("none_0") is not None
    transfer_reaches = dnn.mean_curve_time("regular_100") is not None
    never = dnn.never_learn("none_0")
    verdict = ("reproduced" if transfer_reaches and not none_reaches and never > len(dnn.runs("none_0")) / 2
               else "partly" if transfer_reaches and (not none_reaches or never > 0) else "not reproduced")
    head = ("| row | paper: time to threshold | paper: final <R> | ours: mean curve | ours: final <R> | "
            "runs reaching it | runs that never learn |\n|---|---|---|---|---|---|---|")
    return verdict, [head, *rows]


def claim_6(L: dict[str, Learner]) -> tuple[str, list[str]]:
    dnn = L["IV"]
    lines, slower = [], []
    fails = {"regular": [0, 0], "scaffolded": [0, 0]}
    for n in (1, 15, 50, 100, 5000):
        reg, sca = f"regular_{n}", f"scaffolded_{n}"
        if not dnn.runs(reg) or not dnn.runs(sca):
            continue
        ours = ratio_of_medians(dnn.times(sca), dnn.times(reg))
        slower.append(row_verdict(ours, below=False))  # "slower": scaffolded / regular above 1
        for strategy, cell in (("regular", reg), ("scaffolded", sca)):
            fails[strategy][0] += dnn.never_learn(cell) + len(dnn.cells[cell].failed)
            fails[strategy][1] += len(dnn.runs(cell)) + len(dnn.cells[cell].failed)
        lines.append(f"| N={n} | {_steps(_paper_time(dnn.paper[sca]))} / {_steps(_paper_time(dnn.paper[reg]))} | "
                     f"{_steps(dnn.mean_curve_time(sca))} / {_steps(dnn.mean_curve_time(reg))} | {format_interval(ours)} | "
                     f"{dnn.never_learn(sca)} / {dnn.never_learn(reg)} | {slower[-1]} |")
    if not slower:
        return "undecided", ["Table IV has no transfer runs yet."]
    rate = {k: f / n if n else 0.0 for k, (f, n) in fails.items()}
    need = seeds_to_decide(rate["regular"], rate["scaffolded"])
    lines.append("")
    lines.append(f"Runs that never learn or fail, all N_source: regular {fails['regular'][0]} of "
                 f"{fails['regular'][1]}, scaffolded {fails['scaffolded'][0]} of {fails['scaffolded'][1]}. "
                 + ("Telling these rates apart (two-sided test, α = 0.05, power 0.8) would need about "
                    f"{need:,} runs per strategy." if need else "The rates are equal: no number of seeds tells them apart."))
    # "More robust": fewer failures with scaffolding; decided only with the runs a test needs.
    robust = "undecided" if need is None or need > fails["scaffolded"][1] else (
        "reproduced" if rate["scaffolded"] < rate["regular"] else "against")
    verdict = combine(slower + [robust])
    head = ("| N_source | paper: scaffolded / regular time to threshold | ours, mean curves | ours, "
            "ratio of median per-run times [95 % CI] | runs that never learn, scaffolded / regular | row "
            "(slower) |\n|---|---|---|---|---|---|")
    return verdict, [head, *lines]


def row_verdict(ratio: tuple[float, float, float], paper: float | None = None, below: bool = True) -> str:
    """One row's verdict on a ratio the claim says is below 1 (``below``) or above 1; with the
    paper's factor, 'reproduced' needs our interval to reach it."""
    point, low, high = ratio
    if (high < 1) if below else (low > 1):
        if paper is None or (low <= paper if below else high >= paper):
            return "reproduced"
        return "partly"
    if (low > 1) if below else (high < 1):
        return "against"
    return "undecided" if ((point < 1) if below else (point > 1)) else "absent"


def combine(verdicts: list[str]) -> str:
    """The claim's verdict from its rows' (VERDICT_RULES)."""
    if not verdicts:
        return "undecided"
    if all(v == "reproduced" for v in verdicts):
        return "reproduced"
    if "against" in verdicts:
        return "not reproduced"
    if any(v in ("reproduced", "partly") for v in verdicts):
        return "partly"
    return "undecided" if "undecided" in verdicts else "not reproduced"


CLAIMS = [
    ("RBF: the threshold at ~400k steps without transfer, ~70k with regular (N=50), ~60k with "
     "scaffolded transfer (N=50/100): almost an order of magnitude.", claim_1),
    ("Solving a single source task (N_source = 1) already speeds learning up.", claim_2),
    ("Too many source tasks (N_source = 5000) over-specialise: a worse L_R; for FSR and DNN the "
     "target task is not learned at all.", claim_3),
    ("Scaffolding lowers the time to threshold further for the linear learners (FSR 60k -> 40k).", claim_4),
    ("DNN: without transfer the threshold is never reached (final <R> ~5); regular transfer with "
     "N=100 reaches it at ~220k (final <R> ~9).", claim_5),
    ("DNN with scaffolding is slower at best but more robust to N_source (N=50 reaches the threshold).", claim_6),
]


# --- per cell and per learner ----------------------------------------------------------------------
def cell_table(lr: Learner) -> list[str]:
    out = [f"| {lr.name} row | runs | L_R mean ± SEM | IQM | paper | ratio to none_0 [95 % CI] | "
           "P(improvement) | never learn | time to threshold: mean curve / median per run [95 % CI] |",
           "|---|---:|---:|---:|---:|---|---:|---:|---|"]
    for cell, p in lr.paper.items():
        runs = lr.runs(cell)
        if not runs:
            out.append(f"| {cell} | 0 | | | {p.reward_loss_mean:.1f} | | | | |")
            continue
        losses = lr.losses(cell)
        ratio = "" if cell == "none_0" else format_interval(ratio_of_means(losses, lr.losses("none_0")))
        improve = "" if cell == "none_0" else f"{probability_of_improvement(losses, lr.losses('none_0')):.2f}"
        failed = f" (+{len(lr.cells[cell].failed)} diverged)" if lr.cells[cell].failed else ""
        out.append(f"| {cell} | {len(runs)}{failed} | {losses.mean():.1f} ± {sem(losses):.1f} | {iqm(losses):.1f} | "
                   f"{p.reward_loss_mean:.1f} | {ratio} | {improve} | {lr.never_learn(cell)} | "
                   f"{_steps(lr.mean_curve_time(cell))} / {_median_time(lr.times(cell))} |")
    return out


def split_table(L: dict[str, Learner]) -> list[str]:
    out = ["| learner | row | runs | discovery: first rewarded target episode | learning: discovery -> "
           "first <R> >= 8 | holding: L_R lost after that point |", "|---|---|---:|---|---|---|"]
    for lr in L.values():
        for cell in ("none_0", "regular_50", "scaffolded_50"):
            runs = lr.runs(cell)
            if not runs:
                continue
            discovery = [r.first_target_reward_step for r in runs if r.first_target_reward_step is not None]
            spans = [s for r in runs if (s := learning_span(r.first_target_reward_step, r.steps, r.mean_reward,
                                                            THRESHOLD)) is not None]
            holding = []
            for r in runs:
                first = first_point_at_threshold(r.mean_reward, THRESHOLD)
                if first is not None:
                    holding.append(sum(MAX_REWARD - v for v in r.mean_reward[first:]))
            out.append(f"| {lr.name} | {cell} | {len(runs)} | median {_steps(_median(discovery))} "
                       f"({len(discovery)} of {len(runs)} discover) | median {_steps(_median(spans))} "
                       f"({len(spans)} get there) | median {_median(holding, 1)} |")
    return out


def _median_time(times: np.ndarray) -> str:
    """The median per-run time to threshold with its bootstrap interval (never: slower than any)."""
    point, low, high = bootstrap(median, times)
    return f"{_steps(point)} [{_steps(low)}, {_steps(high)}]"


def _median(values: list, digits: int | None = None):
    if not values:
        return None if digits is None else "n/a"
    m = float(np.median(values))
    return m if digits is None else f"{m:.{digits}f}"


def dqn_failures(L: dict[str, Learner]) -> list[str]:
    dnn = L["IV"]
    runs = dnn.runs("none_0")
    never = [r for r in runs if never_learns(r)]
    return [f"Without transfer, {len(never)} of {len(runs)} DQN runs never reach <R> >= 8; with transfer, "
            f"{sum(dnn.never_learn(c) for c in dnn.cells if c != 'none_0')} of "
            f"{sum(len(dnn.runs(c)) for c in dnn.cells if c != 'none_0')} runs.", "",
            *NEVER_LEARN_COLUMNS, *map(never_learn_row, never), "",
            "Why: a pre-registered ablation of the replay buffer and the ε schedule on fresh seeds, "
            "[dqn_failure_ablation.md](dqn_failure_ablation.md) (`make dqn-ablation`)."]


SHORT_CLAIMS = (
    "RBF: transfer (N=50/100) reaches the threshold almost 10x sooner",
    "a single source task (N_source = 1) already speeds learning up",
    "N_source = 5000 over-specialises (FSR, DNN: not learned at all)",
    "scaffolding lowers the time to threshold further (linear learners)",
    "DNN: never reaches the threshold without transfer, does with regular N=100",
    "DNN: scaffolding slower at best, but more robust to N_source",
)
README_BEGIN = "<!-- headline: generated by python -m mediated_transfer.reporting.reproduction; do not edit -->"
README_END = "<!-- headline: end -->"


def headline(L: dict[str, Learner]) -> str:
    """The README's headline: L_R per table against the paper's, and the six verdicts."""
    out = ["| Table (learner) | runs | L_R without transfer: ours / paper | transfer rows, N_source ≤ 100: "
           "ours / paper | N_source = 5000 (regular, scaffolded): ours / paper |", "|---|---:|---:|---:|---:|"]
    for lr in L.values():
        runs = sum(len(c.results) + len(c.failed) for c in lr.cells.values())
        if not runs:
            continue
        small = [c for c in lr.paper if c != "none_0" and not c.endswith("_5000") and lr.runs(c)]
        ours = [lr.losses(c).mean() for c in small]
        paper = [lr.paper[c].reward_loss_mean for c in small]
        base = lr.losses("none_0")
        big = [f"{lr.losses(c).mean():.1f}" if lr.runs(c) else "-" for c in ("regular_5000", "scaffolded_5000")]
        out.append(f"| {lr.table} ({lr.name}) | {runs}/{len(lr.paper) * EXPECTED_RUNS} | {base.mean():.1f} ± {sem(base):.1f} / "
                   f"{lr.paper['none_0'].reward_loss_mean:.1f} | {min(ours):.1f}-{max(ours):.1f} / "
                   f"{min(paper):.1f}-{max(paper):.1f} | {', '.join(big)} / {lr.paper['regular_5000'].reward_loss_mean:.0f}, "
                   f"{lr.paper['scaffolded_5000'].reward_loss_mean:.0f} |")
    out += ["", "| # | the paper's claim | verdict |", "|---:|---|---|"]
    out += [f"| {i} | {text} | {fn(L)[0]} |" for i, (text, (_, fn)) in enumerate(zip(SHORT_CLAIMS, CLAIMS), 1)]
    return "\n".join(out)


def with_headline(readme: str, block: str) -> str:
    """``readme`` with the text between the headline markers replaced by ``block``."""
    start, end = readme.find(README_BEGIN), readme.find(README_END)
    if start < 0 or end < start:
        raise ValueError(f"README has no headline markers ({README_BEGIN!r} ... {README_END!r})")
    return readme[:start + len(README_BEGIN)] + "\n" + block + "\n" + readme[end:]


def render(L: dict[str, Learner]) -> str:
    counts = {lr.name: sum(len(c.results) + len(c.failed) for c in lr.cells.values()) for lr in L.values()}
    total = {lr.name: len(lr.paper) * EXPECTED_RUNS for lr in L.values()}
    lines = ["# Reproduction: the paper's six claims against our runs", "",
             "Generated by `python -m mediated_transfer.reporting.reproduction` (`make reproduction`) from the "
             "committed paper-scale runs in `multirun/`; do not edit by hand.", "",
             "Runs: " + ", ".join(f"{name} {counts[name]} of {total[name]}" for name in counts) + ".", ""]
    incomplete = [name for name in counts if counts[name] < total[name]]
    if incomplete:
        lines += [f"**Incomplete:** {', '.join(incomplete)} {'has' if len(incomplete) == 1 else 'have'} fewer runs "
                  "than the paper's 20 per row; verdicts that rest on them may change.", ""]
    lines += ["## How a verdict is reached", "", VERDICT_RULES, "", "## Verdicts", "",
              "| # | claim | verdict |", "|---:|---|---|"]
    results = [(text, *fn(L)) for text, fn in CLAIMS]
    lines += [f"| {i} | {text} | **{verdict}** |" for i, (text, verdict, _) in enumerate(results, 1)]
    for i, (text, verdict, body) in enumerate(results, 1):
        lines += ["", f"### Claim {i}: {verdict}", "", f"> {text}", "", *body]
    lines += ["", "## Every row", ""]
    for lr in L.values():
        lines += [f"### Table {lr.table} ({lr.name})", "", *cell_table(lr), ""]
    lines += ["## Where a run's time goes", "",
              "Medians over runs; discovery and learning in learning steps, holding in L_R.", "",
              *split_table(L), "", "## The DQN without transfer: runs that never learn", "", *dqn_failures(L), ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mediated_transfer.reporting.reproduction",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", default=".", help="the checkout whose multirun/ holds the runs")
    parser.add_argument("--out", default=None, help="where to write (default: <root>/reports/REPRODUCTION.md)")
    args = parser.parse_args(argv)
    root = Path(args.root)
    learners = load(root)
    if not any(lr.cells for lr in learners.values()):
        raise SystemExit(f"no paper-scale runs under {root / 'multirun'}: run make reproduce-tables first")
    out = Path(args.out) if args.out else root / "reports" / "REPRODUCTION.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(render(learners))
    print(f"wrote {out}")
    readme = root / "README.md"
    if args.out is None and readme.is_file():  # the headline of the README beside the report
        readme.write_text(with_headline(readme.read_text(), headline(learners)))
        print(f"wrote the headline of {readme}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
