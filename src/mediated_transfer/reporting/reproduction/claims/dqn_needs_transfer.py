"""Claim 5: the DQN never reaches the threshold without transfer (final <R> ~5); with regular
transfer, N_source = 100, it does, at ~220k (final <R> ~9)."""

from __future__ import annotations

import numpy as np

from ....metrics import MetricsConfig
from ...intervals import bootstrap, format_interval, median_interval
from ...verdicts import ABOVE, BELOW, DETAIL, DIRECTION, Part, Row, reaches_threshold, size
from ..claim import Claim
from ..runs import Learner
from ..wording import failed, reaching, steps_k

TEXT = ("DNN: without transfer the threshold is never reached (final <R> ~5); regular transfer with "
        "N=100 reaches it at ~220k (final <R> ~9).")
SHORT = "DNN: never reaches the threshold without transfer, does with regular N=100"
SOURCE = ('Sec. VI: "our (regular) transfer learning scheme (Strategy 1) enables the agent to reach the '
          'threshold performance after ≈220·10³ learning steps and a final performance of ⟨R⟩ ≈ 9 within '
          'the limit of 500·10³ steps. The regular learning only reaches a final performance of ⟨R⟩ ≈ 5"; '
          'Table IV: without transfer "-".')
SCOPE = ("The DNN (Table IV): the row without transfer, and regular transfer with N_source = 100 (the "
         "text's ~220k is that row of Table IV).")


def parts() -> tuple[Part, Part, Part, Part]:
    """The claim's parts, each with the rule that decides it (verdicts.RULES)."""
    return (Part(DIRECTION, "direction", "without transfer the DQN never reaches the threshold, with regular "
                 "transfer (N_source = 100) it does", "R3"),
            Part(DETAIL, "final <R> without transfer", "without transfer a final <R> of only ~5", "R2"),
            Part(DETAIL, "final <R> with transfer", "with regular transfer a final <R> of ~9 or more", "R2"),
            Part(DETAIL, "time", "with regular transfer the threshold by ~220k", "R2"))


def claim_5(learners: dict[str, Learner]) -> Claim:
    dnn = learners["IV"]
    reach, low, high, when = parts()
    all_parts = [reach, low, high, when]
    if not dnn.runs("none_0") or not dnn.runs("regular_100"):
        return Claim(TEXT, SHORT, SOURCE, SCOPE, all_parts, ["Table IV has no runs of these rows yet."])
    for cell, paper_reaches in (("none_0", False), ("regular_100", True)):
        ours = dnn.mean_curve_reaching(cell)
        s = dnn.cells[cell].summary(MetricsConfig())
        reach.rows.append(Row(f"DNN {cell}", steps_k(dnn.paper_time(cell)), reaching(ours),
                              reaches_threshold(ours.share_reaching, paper_reaches),
                              f"{s['runs_reaching_threshold']} of {s['n_runs']} runs reach it; "
                              f"{dnn.never_learn(cell)} never learn{failed(dnn.cells[cell])}"))
    final = {c: bootstrap(np.mean, [r.mean_reward[-1] for r in dnn.runs(c)]) for c in ("none_0", "regular_100")}
    low.rows.append(Row("DNN none_0, mean final <R>", "~5", format_interval(final["none_0"]),
                        size(final["none_0"], 5.0, BELOW, null=None)))
    high.rows.append(Row("DNN regular_100, mean final <R>", "~9", format_interval(final["regular_100"]),
                         size(final["regular_100"], 9.0, ABOVE, null=None)))
    time = median_interval(dnn.times_to_threshold("regular_100"))
    when.rows.append(Row("DNN regular_100, median per-run time to threshold", steps_k(dnn.paper_time("regular_100")),
                         f"{steps_k(time[0])} [{steps_k(time[1])}, {steps_k(time[2])}]",
                         size(time, dnn.paper_time("regular_100"), BELOW, null=None),
                         f"mean curve {steps_k(dnn.mean_curve_time('regular_100'))}; sooner is beyond the paper's"))
    reach.evidence = "; ".join(f"{r.label.split()[1]} {r.ours}" for r in reach.rows)
    for part in (low, high, when):
        part.evidence = f"ours {part.rows[0].ours}, the paper's {part.rows[0].paper}"
    return Claim(TEXT, SHORT, SOURCE, SCOPE, all_parts)
