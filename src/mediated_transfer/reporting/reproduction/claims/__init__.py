"""The paper's six headline claims, in the order NOTES.md numbers them, one module each: the
claim's words, the rows it covers, its parts with the rule that decides each (verdicts.py), and
how its rows are read from the runs."""

from __future__ import annotations

from ...verdicts import VERDICTS
from ..claim import Claim
from ..runs import Learner
from .dqn_needs_transfer import claim_5
from .dqn_scaffolding import claim_6
from .rbf_speedup import claim_1
from .scaffolding_linear import claim_4
from .single_source_task import claim_2, same_runs
from .too_many_source_tasks import claim_3

CLAIMS = [claim_1, claim_2, claim_3, claim_4, claim_5, claim_6]

__all__ = ["CLAIMS", "claim_1", "claim_2", "claim_3", "claim_4", "claim_5", "claim_6", "evaluate", "same_runs",
           "verdict_count"]


def evaluate(learners: dict[str, Learner]) -> list[Claim]:
    return [fn(learners) for fn in CLAIMS]


def verdict_count(claims: list[Claim]) -> str:
    """How many claims got each verdict, e.g. '1 reproduced, 3 partly, 2 not reproduced, 0 undecided'."""
    return ", ".join(f"{sum(c.verdict == v for c in claims)} {v}" for v in VERDICTS)
