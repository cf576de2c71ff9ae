"""``python -m mediated_transfer.reporting.reproduction``: reports/REPRODUCTION.md, a verdict on
each of the paper's six headline claims (shared NOTES.md), from the committed paper-scale runs
of Tables II-IV, and the README's headline beside it. Nothing in it is typed: every number comes
from the runs' result.json files, the paper's from paper_tables.csv.

Per claim (claims/, one module each): the paper's words it is read from, the learners and rows
they name, and the claim split into its parts (direction, size, a named example, "not learned at
all"), each declared with the rule of verdicts.py that decides it (``RULES``); the claim's verdict
derived from its parts'. Ratios (transfer row / reference row) of L_R and of the per-run time to
threshold carry 95 % bootstrap intervals over runs. Per row (tables.py): IQM, probability of
improvement over the row without transfer, and runs that never learn (no evaluation point at
<R> >= 8) counted apart from the mean. Per learner: where a run's time goes, discovery (first
rewarded target episode), learning (discovery to first <R> >= 8), holding (L_R lost after that
point).

runs.py loads the runs, document.py writes the report, headline.py the README's headline,
command.py is the command line. The names below are the package's public ones.
"""

from .claim import Claim
from .claims import CLAIMS, claim_1, claim_2, claim_3, claim_4, claim_5, claim_6, evaluate, same_runs, verdict_count
from .command import main
from .document import render
from .headline import headline, with_headline
from .runs import Learner, load

__all__ = ["CLAIMS", "Claim", "Learner", "claim_1", "claim_2", "claim_3", "claim_4", "claim_5", "claim_6",
           "evaluate", "headline", "load", "main", "render", "same_runs", "verdict_count", "with_headline"]
