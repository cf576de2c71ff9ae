"""Claim 4: for the linear learners, scaffolded transfer lowers the time to threshold further than
regular transfer."""

from __future__ import annotations

from ...intervals import format_interval, ratio_of_medians
from ...verdicts import BELOW, DETAIL, DIRECTION, Part, direction, size
from ..claim import Claim
from ..runs import Learner
from ..wording import median_times, ratio_row, span, steps_k

TEXT = "Scaffolding lowers the time to threshold further for the linear learners (FSR 60k -> 40k)."
SHORT = "scaffolding lowers the time to threshold further (linear learners)"
SOURCE = ('Sec. VI: "For the linear Q-learning, adding scaffolding to the transfer learning scheme (Strategy 2) '
          'is able to reduce the time needed to reach the threshold performance again. ... reduced from '
          '≈400·10³ to ≈60·10³ learning steps by scaffolded transfer learning, while regular transfer '
          'learning reduces the learning steps to ≈70·10³." and "For the binary representation (FSR), '
          'scaffolded transfer learning is also able to again reduce the required training time from '
          '≈60·10³ to ≈40·10³ steps."')
SCOPE = ("The linear learners. RBF: the text's scaffolded ~60k stands in Table II's N_source = 50 and 100, "
         "its regular ~70k in N_source = 50. FSR: scaffolded ~40k is Table III's N_source = 15, regular "
         "~60k its N_source = 15 and 50. In the paper's own tables scaffolding is not faster at RBF "
         "N_source = 15 (80k and 80k) and slower at FSR N_source = 50 (100k against 60k).")
ROWS = (("II", "scaffolded_50", "regular_50"), ("II", "scaffolded_100", "regular_50"),
        ("III", "scaffolded_15", "regular_15"), ("III", "scaffolded_15", "regular_50"))
"""The pairs whose times Sec. VI quotes: RBF ~60k (Table II scaffolded 50 and 100) against ~70k
(regular 50); FSR ~40k (Table III scaffolded 15) against ~60k (regular 15 and 50)."""


def parts() -> tuple[Part, Part]:
    """The claim's parts, each with the rule that decides it (verdicts.RULES)."""
    return (Part(DIRECTION, "direction", "scaffolded transfer reaches the threshold sooner than regular", "R1"),
            Part(DETAIL, "size", "by the paper's factor (RBF 70k -> 60k, FSR 60k -> 40k)", "R2"))


def claim_4(learners: dict[str, Learner]) -> Claim:
    direction_part, size_part = parts()
    points = []
    for table, a, b in ROWS:
        lr = learners[table]
        if not lr.runs(a) or not lr.runs(b):
            continue
        ours = ratio_of_medians(lr.times_to_threshold(a), lr.times_to_threshold(b))
        factor = lr.paper_time(a) / lr.paper_time(b)
        paper = f"{steps_k(lr.paper_time(a))} / {steps_k(lr.paper_time(b))} = {factor:.2f}"
        direction_part.rows.append(ratio_row(f"{lr.name} {a} / {b}", paper, ours, median_times(lr, a, b),
                                             direction(ours, BELOW)))
        size_part.rows.append(ratio_row(f"{lr.name} {a} / {b}", paper, ours, "", size(ours, factor, BELOW)))
        points.append(ours[0])
    direction_part.evidence = f"ratios {span(points)}" if points else ""
    example = next((r for r in size_part.rows if r.label == "FSR scaffolded_15 / regular_15"), None)
    size_part.evidence = (f"the paper's FSR example {example.paper}, ours {example.ours}" if example else "")
    return Claim(TEXT, SHORT, SOURCE, SCOPE, [direction_part, size_part], _same_n_source(learners))


def _same_n_source(learners: dict[str, Learner]) -> list[str]:
    """The rows with the same N_source that the text does not name: shown, not counted (R7)."""
    shown = ["Not counted: the rows with the same N_source that the text does not name.", "",
             "| learner | N_source | paper: scaffolded / regular | ours, median per run | ours, ratio of medians "
             "[95 % CI] | R1 |", "|---|---|---|---|---|---|"]
    for table in ("II", "III"):
        lr = learners[table]
        for n in (15, 50, 100):
            a, b = f"scaffolded_{n}", f"regular_{n}"
            if (table, a, b) in ROWS or not lr.runs(a) or not lr.runs(b):
                continue
            ours = ratio_of_medians(lr.times_to_threshold(a), lr.times_to_threshold(b))
            p = lr.paper_time(a) / lr.paper_time(b)
            shown.append(f"| {lr.name} | {n} | {steps_k(lr.paper_time(a))} / {steps_k(lr.paper_time(b))} = {p:.2f} | "
                         f"{median_times(lr, a, b)[:-2]} | {format_interval(ours)} | {direction(ours, BELOW)} |")
    return shown
