"""Claim 2: solving a single source task (N_source = 1) already speeds learning of the target task
up, for the linear learners."""

from __future__ import annotations

from ...intervals import format_interval, ratio_of_means, ratio_of_medians
from ...verdicts import BELOW, DIRECTION, Part, direction
from ..claim import Claim
from ..runs import Learner
from ..wording import median_times, ratio_row, span, steps_k

TEXT = "Solving a single source task (N_source = 1) already speeds learning up."
SHORT = "a single source task (N_source = 1) already speeds learning up (linear learners)"
SOURCE = ('Sec. VI: "The first notable point listed in both tables of the linear function approximators '
          'is that the agent has just to solve the source task one single time (N_source = 1) to get a '
          'favorable seeding of the Q-values that is sufficiently good enough to speed up the target task."')
SCOPE = ("The linear learners (Tables II and III). With N_source = 1 both strategies present the one "
         "source task until it is solved, so regular_1 and scaffolded_1 are the same runs and count once; "
         "the paper's Tables report both (RBF: L_R 44.8 and 42.3).")


def parts() -> tuple[Part]:
    """The claim's part, with the rule that decides it (verdicts.RULES)."""
    return (Part(DIRECTION, "direction", "a single source task speeds up learning of the target task", "R1"),)


def same_runs(learner: Learner, a: str, b: str) -> tuple[int, int]:
    """(seeds whose curves are identical in rows a and b, seeds run in both): rows that are the
    same runs count once (R7)."""
    curves = {r.seed: r.mean_reward for r in learner.runs(b)}
    common = [r for r in learner.runs(a) if r.seed in curves]
    return sum(r.mean_reward == curves[r.seed] for r in common), len(common)


def claim_2(learners: dict[str, Learner]) -> Claim:
    part, = parts()
    shown = ["Not counted: the DNN, outside the claim's text (the paper's own ratios of L_R at N_source = 1 "
             "are 0.79 and 1.00).", "",
             "| learner | row | paper | ours [95 % CI] | same runs |", "|---|---|---|---|---|"]
    points = []
    for table in ("II", "III", "IV"):
        lr = learners[table]
        if not lr.runs("none_0") or not lr.runs("regular_1"):
            continue
        identical, n = same_runs(lr, "regular_1", "scaffolded_1")
        cells = ["regular_1"] if identical == n == len(lr.runs("regular_1")) else ["regular_1", "scaffolded_1"]
        for cell in cells:
            label = "regular_1 = scaffolded_1" if len(cells) == 1 else cell
            paper_ratio = " and ".join(f"{lr.paper[c].reward_loss_mean / lr.paper['none_0'].reward_loss_mean:.2f}"
                                       for c in ("regular_1", "scaffolded_1") if len(cells) == 1 or c == cell)
            loss = ratio_of_means(lr.reward_losses(cell), lr.reward_losses("none_0"))
            time = ratio_of_medians(lr.times_to_threshold(cell), lr.times_to_threshold("none_0"))
            if table == "IV":  # outside the claim (R7)
                shown.append(f"| {lr.name} | {cell} / none_0, L_R | {paper_ratio} | {format_interval(loss)} | "
                             f"{identical} of {n} curves identical |")
                continue
            same = f"the same {n} runs ({identical} of {n} curves identical)" if len(cells) == 1 else ""
            part.rows.append(ratio_row(f"{lr.name} {label} / none_0, mean L_R", paper_ratio, loss, "",
                                       direction(loss, BELOW), same))
            part.rows.append(ratio_row(
                f"{lr.name} {label} / none_0, median time to threshold",
                f"{steps_k(lr.paper_time(cell))} / {steps_k(lr.paper_time('none_0'))}",
                time, median_times(lr, cell, "none_0"), direction(time, BELOW), same))
            points += [loss[0], time[0]]
    part.evidence = f"ratios {span(points)}" if points else ""
    return Claim(TEXT, SHORT, SOURCE, SCOPE, [part], shown)
