"""Claim 3: too many source tasks (N_source = 5000) over-specialise the learner on the source task:
a higher reward loss, a later threshold, and for FSR and DNN a target task not learned at all."""

from __future__ import annotations

from ...intervals import format_interval, ratio_of_means, ratio_of_medians
from ...verdicts import ABOVE, DETAIL, DIRECTION, Part, Row, direction, not_learned_at_all
from ..claim import Claim
from ..runs import Learner
from ..wording import median_times, ratio_row, span, steps_k

TEXT = ("Too many source tasks (N_source = 5000) over-specialise: a worse L_R; for FSR and DNN the "
        "target task is not learned at all.")
SHORT = "N_source = 5000 over-specialises (FSR, DNN: not learned at all)"
SOURCE = ('Sec. VI: "The best performance, with a minimal L_R can then be achieved for N_source = 50 (RBF), '
          'N_source = 15 (FSR) and N_source = 100 (DNN). If N_source gets large, the learning process '
          'becomes too specialized on the source task. This phenomenon leads to an increase of L_R and the '
          'learning time to reach the performance threshold ... The extreme case of N_source = 5000 '
          'suppresses the learning of the target task for the learning process with the binary '
          'representation and the deep neural network."')
SCOPE = ("All three learners, both strategies: N_source = 5000 against the same strategy at the N_source "
         "the text names as best (RBF 50, FSR 15, DNN 100). Not learned at all: FSR and DNN, both "
         "strategies (the paper's L_R 223-246 of 250, threshold never reached).")
BEST_N_SOURCE = {"II": 50, "III": 15, "IV": 100}
"""The N_source with the lowest L_R, as Sec. VI names it per learner (RBF 50, FSR 15, DNN 100)."""


def parts() -> tuple[Part, Part, Part]:
    """The claim's parts, each with the rule that decides it (verdicts.RULES)."""
    return (Part(DIRECTION, "higher L_R", "N_source = 5000 has a higher L_R than the best N_source", "R1"),
            Part(DIRECTION, "later threshold", "and reaches the threshold later", "R1"),
            Part(DETAIL, "not learned at all", "FSR and DNN with N_source = 5000: not learned at all", "R4"))


def claim_3(learners: dict[str, Learner]) -> Claim:
    loss_part, time_part, unlearned = parts()
    loss_points, time_points, never = [], [], []
    for table in ("II", "III", "IV"):
        lr = learners[table]
        for strategy in ("regular", "scaffolded"):
            cell, best = f"{strategy}_5000", f"{strategy}_{BEST_N_SOURCE[table]}"
            if not lr.runs(cell) or not lr.runs(best):
                continue
            loss = ratio_of_means(lr.reward_losses(cell), lr.reward_losses(best))
            p = lr.paper[cell].reward_loss_mean / lr.paper[best].reward_loss_mean
            loss_part.rows.append(ratio_row(
                f"{lr.name} {cell} / {best}",
                f"{lr.paper[cell].reward_loss_mean:.1f} / {lr.paper[best].reward_loss_mean:.1f} = {p:.2f}", loss,
                f"{lr.reward_losses(cell).mean():.1f} / {lr.reward_losses(best).mean():.1f}: ",
                direction(loss, ABOVE)))
            time = ratio_of_medians(lr.times_to_threshold(cell), lr.times_to_threshold(best))
            time_part.rows.append(ratio_row(
                f"{lr.name} {cell} / {best}", f"{steps_k(lr.paper_time(cell))} / {steps_k(lr.paper_time(best))}",
                time, median_times(lr, cell, best), direction(time, ABOVE)))
            loss_points.append(loss[0])
            time_points.append(time[0])
            if lr.paper[cell].time_to_threshold is None:  # the paper's rows "not learned at all"
                n, k = len(lr.runs(cell)), lr.never_learn(cell)
                vs_none = format_interval(ratio_of_means(lr.reward_losses(cell), lr.reward_losses("none_0")))
                unlearned.rows.append(Row(
                    f"{lr.name} {cell}", f"L_R {lr.paper[cell].reward_loss_mean:.0f} of 250, threshold never",
                    f"{k} of {n} runs never reach <R> >= 8; L_R {lr.reward_losses(cell).mean():.1f}",
                    not_learned_at_all(k, n), f"L_R ratio to without transfer {vs_none}"))
                never.append(f"{lr.name} {strategy} {k} of {n}")
    loss_part.evidence = f"ratios {span(loss_points)}"
    time_part.evidence = f"ratios {span(time_points)}"
    unlearned.evidence = "runs that never learn: " + ", ".join(never)
    return Claim(TEXT, SHORT, SOURCE, SCOPE, [loss_part, time_part, unlearned])
