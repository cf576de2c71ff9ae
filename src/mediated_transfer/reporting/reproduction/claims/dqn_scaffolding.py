"""Claim 6: for the DQN, scaffolded transfer reaches the threshold later than regular (~220k ->
~310k) but is more robust to N_source (with N_source = 50 it reaches the threshold, regular does not)."""

from __future__ import annotations

import numpy as np

from ....metrics import MetricsConfig
from ...intervals import bootstrap, format_interval, ratio_of_medians, seeds_to_decide
from ...verdicts import ABOVE, BELOW, DETAIL, DIRECTION, Part, Row, direction, reaches_threshold, size
from ..claim import Claim
from ..runs import Learner, never_learns
from ..wording import failed, median_times, ratio_row, reaching, steps_k

TEXT = ("DNN with scaffolding is slower (~220k -> ~310k) but more robust to N_source (N=50 reaches the "
        "threshold).")
SHORT = "DNN: scaffolding slower (~220k -> ~310k), but more robust to N_source"
SOURCE = ('Sec. VI: "For the deep Q-learner, the required time to reach the threshold performance is '
          'increasing from ≈220·10³ to ≈310·10³ steps when using the scaffolded transfer learning approach. '
          'However, the scaffolded approach is much more robust on changes of N_source, as now the learning '
          'runs with N_source = 50 are also able to reach a success rate above 80%."')
SCOPE = ("The DNN (Table IV). The text's ~220k is regular N_source = 100, its ~310k scaffolded "
         "N_source = 15 (each strategy's fastest row). Robustness: the paper shows it as rows that reach "
         "the threshold (scaffolded 3 of 5, regular 2 of 5); ours is read per run over all five N_source, "
         "where a share has an interval. The example: N_source = 50, regular \"-\", scaffolded ~360k.")
N_SOURCES = (1, 15, 50, 100, 5000)
SLOWER = ("scaffolded_15", "regular_100")
"""(scaffolded, regular): each strategy's fastest row, the ~310k and ~220k the text compares."""


def parts() -> tuple[Part, Part, Part, Part]:
    """The claim's parts, each with the rule that decides it (verdicts.RULES)."""
    return (Part(DIRECTION, "slower", "scaffolded transfer reaches the threshold later than regular", "R1"),
            Part(DETAIL, "size", "by the paper's factor (220k -> 310k)", "R2"),
            Part(DIRECTION, "more robust", "scaffolded transfer is more robust to N_source: fewer runs "
                 "that never learn", "R1"),
            Part(DETAIL, "example", "with N_source = 50 scaffolded transfer reaches the threshold and "
                 "regular does not", "R3"))


def claim_6(learners: dict[str, Learner]) -> Claim:
    dnn = learners["IV"]
    slower, factor_part, robust, example = parts()
    all_parts = [slower, factor_part, robust, example]
    cells = [f"{s}_{n}" for s in ("regular", "scaffolded") for n in N_SOURCES]
    if not all(dnn.runs(c) for c in cells):
        return Claim(TEXT, SHORT, SOURCE, SCOPE, all_parts, ["Table IV has no runs of every transfer row yet."])
    a, b = SLOWER
    ours = ratio_of_medians(dnn.times_to_threshold(a), dnn.times_to_threshold(b))
    factor = dnn.paper_time(a) / dnn.paper_time(b)
    paper = f"{steps_k(dnn.paper_time(a))} / {steps_k(dnn.paper_time(b))} = {factor:.2f}"
    note = f"mean curves {steps_k(dnn.mean_curve_time(a))} / {steps_k(dnn.mean_curve_time(b))}"
    slower.rows.append(ratio_row(f"DNN {a} / {b}", paper, ours, median_times(dnn, a, b), direction(ours, ABOVE), note))
    factor_part.rows.append(ratio_row(f"DNN {a} / {b}", paper, ours, "", size(ours, factor, ABOVE)))
    slower.evidence = factor_part.evidence = f"ours {format_interval(ours)}, the paper's {factor:.2f}"
    row, robust.evidence = _robustness(dnn)
    robust.rows.append(row)
    for cell, paper_reaches in (("scaffolded_50", True), ("regular_50", False)):
        ours = dnn.mean_curve_reaching(cell)
        s = dnn.cells[cell].summary(MetricsConfig())
        example.rows.append(Row(f"DNN {cell}", steps_k(dnn.paper_time(cell)), reaching(ours),
                                reaches_threshold(ours.share_reaching, paper_reaches),
                                f"{s['runs_reaching_threshold']} of {s['n_runs']} runs reach it{failed(dnn.cells[cell])}"))
    example.evidence = "; ".join(f"{r.label.split()[-1]} {r.ours}" for r in example.rows)
    return Claim(TEXT, SHORT, SOURCE, SCOPE, all_parts, _same_n_source(dnn))


def _robustness(dnn: Learner) -> tuple[Row, str]:
    """The share of runs that never learn (or failed), scaffolded minus regular, over every
    N_source: the paper shows robustness as rows reaching the threshold, a share of runs has an
    interval (R1), and R8 adds how many runs would tell the shares apart. And its evidence."""
    failing = {}  # per strategy: 1 for each run that never learns or failed, 0 for each that learned
    for strategy in ("regular", "scaffolded"):
        flags = []
        for n in N_SOURCES:
            cell = f"{strategy}_{n}"
            flags += [float(never_learns(r)) for r in dnn.runs(cell)] + [1.0] * len(dnn.cells[cell].failed)
        failing[strategy] = np.array(flags)
    share = bootstrap(lambda s, r: s.mean() - r.mean(), failing["scaffolded"], failing["regular"])
    rate = {k: v.mean() for k, v in failing.items()}
    need = seeds_to_decide(rate["regular"], rate["scaffolded"])
    paper_rows_reached = {s: [n for n in N_SOURCES if dnn.paper[f"{s}_{n}"].time_to_threshold]
                          for s in ("regular", "scaffolded")}
    ours_rows_reached = {s: [n for n in N_SOURCES if dnn.mean_curve_time(f"{s}_{n}") is not None]
                         for s in ("regular", "scaffolded")}
    counts = {k: f"{int(v.sum())} of {v.size}" for k, v in failing.items()}
    row = Row(
        "DNN, all N_source: share of runs that never learn, scaffolded - regular",
        "rows reaching the threshold: scaffolded " + _n_list(paper_rows_reached["scaffolded"])
        + ", regular " + _n_list(paper_rows_reached["regular"]),
        f"scaffolded {counts['scaffolded']}, regular {counts['regular']}: {format_interval(share)}",
        direction(share, BELOW, null=0.0),
        "rows reaching the threshold (mean curve): scaffolded " + _n_list(ours_rows_reached["scaffolded"])
        + ", regular " + _n_list(ours_rows_reached["regular"]) + "; R8: "
        + (f"telling {rate['scaffolded']:.0%} from {rate['regular']:.0%} apart would need about {need:,} runs "
           "per strategy" if need else "the shares are equal, no number of runs tells them apart"))
    return row, f"never learn: scaffolded {counts['scaffolded']}, regular {counts['regular']}"


def _n_list(ns: list[int]) -> str:
    return f"{len(ns)} of 5" + (f" (N_source {', '.join(map(str, ns))})" if ns and len(ns) < 5 else "")


def _same_n_source(dnn: Learner) -> list[str]:
    """The same-N_source rows, which the text does not compare: shown, not counted (R7)."""
    shown = ["Not counted: the same-N_source rows (the text compares regular N_source = 100 with scaffolded "
             "N_source = 15).", "",
             "| N_source | paper: scaffolded / regular | ours, mean curves | ours, ratio of median per-run times "
             "[95 % CI] | runs that never learn, scaffolded / regular | R1 (slower) |", "|---|---|---|---|---|---|"]
    for n in N_SOURCES:
        reg, sca = f"regular_{n}", f"scaffolded_{n}"
        r = ratio_of_medians(dnn.times_to_threshold(sca), dnn.times_to_threshold(reg))
        shown.append(f"| {n} | {steps_k(dnn.paper_time(sca))} / {steps_k(dnn.paper_time(reg))} | "
                     f"{steps_k(dnn.mean_curve_time(sca))} / {steps_k(dnn.mean_curve_time(reg))} | "
                     f"{format_interval(r)} | {dnn.never_learn(sca)} / {dnn.never_learn(reg)} | "
                     f"{direction(r, ABOVE)} |")
    return shown
