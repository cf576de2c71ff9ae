"""Claim 1: for RBF, transfer reaches the threshold almost an order of magnitude sooner."""

from __future__ import annotations

from ...intervals import ratio_of_medians
from ...verdicts import BELOW, DETAIL, DIRECTION, Part, direction, size
from ..claim import Claim
from ..runs import Learner
from ..wording import median_times, ratio_row, span, steps_k

TEXT = ("RBF: the threshold at ~400k steps without transfer, ~70k with regular (N=50), ~60k with "
        "scaffolded transfer (N=50/100): almost an order of magnitude.")
SHORT = "RBF: transfer (N=50/100) reaches the threshold almost 10x sooner"
SOURCE = ('Sec. VI: "the time to reach a stable average success rate of 80% ... can be reduced from '
          '≈400·10³ to ≈60·10³ learning steps by scaffolded transfer learning, while regular transfer '
          'learning reduces the learning steps to ≈70·10³"; abstract and Sec. VII: "an overall '
          'speed-up factor of almost one order of magnitude".')
SCOPE = ("RBF (Table II). The text's ~60k stands in Table II's scaffolded rows with N_source = 50 "
         "and 100, its ~70k in regular N_source = 50, its ~400k in the row without transfer.")
ROWS = (("regular_50", "none_0"), ("scaffolded_50", "none_0"), ("scaffolded_100", "none_0"))
"""(transfer row, reference row): the rows the text's numbers stand in."""


def parts() -> tuple[Part, Part]:
    """The claim's parts, each with the rule that decides it (verdicts.RULES)."""
    return (Part(DIRECTION, "direction", "transfer reaches the threshold sooner", "R1"),
            Part(DETAIL, "size", "by almost an order of magnitude (the paper's factors)", "R2"))


def claim_1(learners: dict[str, Learner]) -> Claim:
    rbf = learners["II"]
    direction_part, size_part = parts()
    ours_points, paper_factors = [], []
    for a, b in ROWS:
        ours = ratio_of_medians(rbf.times_to_threshold(a), rbf.times_to_threshold(b))
        factor = rbf.paper_time(a) / rbf.paper_time(b)
        paper = f"{steps_k(rbf.paper_time(a))} / {steps_k(rbf.paper_time(b))} = {factor:.2f}"
        note = f"mean curves {steps_k(rbf.mean_curve_time(a))} / {steps_k(rbf.mean_curve_time(b))}"
        direction_part.rows.append(ratio_row(f"RBF {a} / {b}", paper, ours, median_times(rbf, a, b),
                                             direction(ours, BELOW), note))
        size_part.rows.append(ratio_row(f"RBF {a} / {b}", paper, ours, "", size(ours, factor, BELOW)))
        ours_points.append(ours[0])
        paper_factors.append(factor)
    direction_part.evidence = f"ratios of median per-run times {span(ours_points)}"
    size_part.evidence = f"ours {span(ours_points)}, the paper's {span(paper_factors)}"
    return Claim(TEXT, SHORT, SOURCE, SCOPE, [direction_part, size_part])
