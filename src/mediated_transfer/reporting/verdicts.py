"""The rules that turn the reproduction's estimates into verdicts, in one place.

``RULES`` is the text REPRODUCTION.md prints; each function below applies one of its rules, and
nothing else decides a verdict (a power calculation may add how many runs a decision would need,
never change one). tests/test_verdicts.py checks every branch of every rule on synthetic numbers,
so the code cannot drift from the text.

A claim of the paper is split into *parts* (what it says about the direction, the size, a named
example, "not learned at all"); a part is decided on *rows* (one estimate each, against the
paper's statement); a part's verdict comes from its rows' outcomes (R5), the claim's from its
parts' verdicts (R6).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

# Outcomes of one row.
HOLDS = "holds"
OTHER_WAY = "holds the other way"  # R1
ABSENT = "absent"  # R1
UNDECIDED = "undecided"  # R1, R2, R3
SHORT = "falls short"  # R2
FAILS = "does not hold"  # R3, R4
AGAINST = (OTHER_WAY, SHORT, FAILS)
OUTCOMES = (HOLDS, OTHER_WAY, ABSENT, UNDECIDED, SHORT, FAILS)

# Verdicts of a part and of a claim.
REPRODUCED = "reproduced"
PARTLY = "partly"
NOT_REPRODUCED = "not reproduced"
VERDICTS = (REPRODUCED, PARTLY, NOT_REPRODUCED, UNDECIDED)

# The kinds of part: a claim's direction parts carry it (R6); the others state its details.
DIRECTION = "direction"
DETAIL = "detail"

BELOW, ABOVE = "below", "above"
"""Which side of the reference the claim puts a value: a ratio below 1 (faster, less loss), above 1
(slower, more loss), a final <R> above the paper's ~9, a share of failures below the other's."""

RULES = """\
**R1, direction.** An estimate is a ratio (transfer row / reference row, of mean L_R or of the
median per-run time to threshold; a run that never reaches the threshold counts as slower than any
that does) or a difference (of the shares of runs that never learn), with a 95 % percentile
bootstrap interval over runs (10,000 resamples, seeded). No difference is 1 for a ratio, 0 for a
difference. A row **holds** when its interval lies entirely on the claim's side of no difference;
it **holds the other way** when the interval lies entirely on the other side; it is **undecided**
when the interval includes no difference and the point estimate is on the claim's side; it is
**absent** when the interval includes no difference and the point estimate is at no difference or
on the other side.

**R2, size.** Where the paper gives a number (a factor, a step count, a final <R>), a row
**holds** when our interval includes the paper's number or lies beyond it on the claim's side,
and, for a ratio, excludes no difference (R1 holds); it **falls short** when the interval lies
entirely on the other side of the paper's number; it is **undecided** when the interval includes
both the paper's number and no difference.

**R3, reaching the threshold.** Where the paper says a row reaches the threshold or never does,
ours is read as the paper reads its own, from the row's mean curve over its runs (those that ran
their budget, as in every statistic of a row; a run stopped as failed is named beside it, not
averaged): its time to threshold is the first evaluation point from which it stays at <R> >= 8 to
the end of the budget, never when it ends below. The uncertainty is a 95 % percentile bootstrap
over runs (10,000 resamples, seeded, as R1): the share of resamples whose mean curve reaches the
threshold, shown beside the interval of the mean curve's time to threshold (never = beyond the
budget). The row **holds** when the paper's statement (it reaches the threshold, or never does)
holds in at least 97.5 % of resamples, as R1 asks the whole interval on the claim's side; it
**does not hold** when the opposite holds in at least 97.5 % of resamples; it is **undecided**
otherwise.

**R4, "not learned at all".** A row the paper says is not learned at all **holds** when more than
half of its runs never reach <R> >= 8 at any evaluation point, and **does not hold** otherwise.

**R5, a part from its rows.** A part is **reproduced** when every row holds; **not reproduced**
when a row holds the other way, falls short or does not hold, or when every row is absent;
**partly** when a row holds and none goes against; **undecided** otherwise (no row holds, none
goes against, at least one is undecided).

**R6, a claim from its parts.** A claim's direction parts say which way the difference goes
(transfer is faster, N_source = 5000 is worse, ...); its other parts give a size, a named example
or "not learned at all". A claim is **reproduced** when every part is; **partly** when a direction
part is reproduced or partly but not every part is reproduced; **not reproduced** when no
direction part is reproduced or partly and some part is not reproduced; **undecided** otherwise.

**R7, rows.** A part's rows are those the paper's text names (quoted under each claim); where a
number the text quotes stands in two rows of its table, both are rows. Rows that are the same
runs count once (with N_source = 1 regular and scaffolded transfer present the same single
source task: for the linear learners the two rows are the same 20 curves). Other rows are shown
for information and not counted.

**R8, power.** Beside a row the report may give the runs per group that a two-sided
two-proportion test (α = 0.05, power 0.8) would need to tell two shares apart. It never changes
an outcome or a verdict."""


# --- R1 -----------------------------------------------------------------------------------------
def direction(interval: tuple[float, float, float], side: str, null: float = 1.0) -> str:
    """R1: the outcome of an estimate (point, low, high) that the claim puts on ``side`` of
    ``null`` (1 for a ratio, 0 for a difference)."""
    point, low, high = _checked(interval, side)
    claim_side = high < null if side == BELOW else low > null
    other_side = low > null if side == BELOW else high < null
    if claim_side:
        return HOLDS
    if other_side:
        return OTHER_WAY
    points_the_claims_way = point < null if side == BELOW else point > null
    return UNDECIDED if points_the_claims_way else ABSENT


# --- R2 -----------------------------------------------------------------------------------------
def size(interval: tuple[float, float, float], paper: float, side: str, null: float | None = 1.0) -> str:
    """R2: the outcome of an estimate against the paper's number ``paper``, which the claim puts
    on ``side`` (of ``null`` for a ratio; ``null=None`` for a value with no 'no difference',
    such as a final <R> or a step count)."""
    _, low, high = _checked(interval, side)
    reaches = low <= paper if side == BELOW else high >= paper
    if not reaches:
        return SHORT
    if null is None or direction(interval, side, null) == HOLDS:
        return HOLDS
    return UNDECIDED


# --- R3, R4 -------------------------------------------------------------------------------------
DECIDING_SHARE = 0.975
"""R3: the share of resamples a statement (reaches, or never does) must hold in to decide a row,
the upper end of a 95 % interval."""
_SLACK = 1e-9
"""Float round-off of a share (1 - 0.975 is not exactly 0.025): 250 of 10,000 resamples is 2.5 %."""


def reaches_threshold(share_reaching: float, paper_reaches: bool) -> str:
    """R3: ``share_reaching`` is the share of bootstrap resamples of the row's runs whose mean curve
    reaches the threshold; the paper says the row reaches it (``paper_reaches``) or never does."""
    if math.isnan(share_reaching) or not 0.0 <= share_reaching <= 1.0:
        raise ValueError(f"{share_reaching} is not a share of resamples")
    as_the_paper = share_reaching if paper_reaches else 1.0 - share_reaching
    if as_the_paper >= DECIDING_SHARE - _SLACK:
        return HOLDS
    if as_the_paper <= 1.0 - DECIDING_SHARE + _SLACK:
        return FAILS
    return UNDECIDED


def not_learned_at_all(never_learn: int, runs: int) -> str:
    """R4: more than half of ``runs`` never reach <R> >= 8."""
    if runs <= 0 or not 0 <= never_learn <= runs:
        raise ValueError(f"{never_learn} of {runs} runs is not a count of runs")
    return HOLDS if never_learn > runs / 2 else FAILS


# --- R5, R6 -------------------------------------------------------------------------------------
def part_verdict(outcomes: list[str]) -> str:
    """R5: a part's verdict from its rows' outcomes."""
    unknown = set(outcomes) - set(OUTCOMES)
    if unknown:
        raise ValueError(f"unknown outcomes {sorted(unknown)}; allowed: {', '.join(OUTCOMES)}")
    if not outcomes:
        return UNDECIDED
    if all(o == HOLDS for o in outcomes):
        return REPRODUCED
    if any(o in AGAINST for o in outcomes) or all(o == ABSENT for o in outcomes):
        return NOT_REPRODUCED
    if HOLDS in outcomes:
        return PARTLY
    return UNDECIDED


def claim_verdict(parts: list[tuple[str, str]]) -> str:
    """R6: a claim's verdict from its parts, given as (kind, verdict) with kind DIRECTION or
    DETAIL."""
    for kind, verdict in parts:
        if kind not in (DIRECTION, DETAIL) or verdict not in VERDICTS:
            raise ValueError(f"a part is (direction|detail, {'|'.join(VERDICTS)}), not ({kind}, {verdict})")
    if not any(kind == DIRECTION for kind, _ in parts):
        raise ValueError("a claim needs a direction part")
    verdicts = [v for _, v in parts]
    if all(v == REPRODUCED for v in verdicts):
        return REPRODUCED
    if any(kind == DIRECTION and v in (REPRODUCED, PARTLY) for kind, v in parts):
        return PARTLY
    if NOT_REPRODUCED in verdicts:
        return NOT_REPRODUCED
    return UNDECIDED


def _checked(interval: tuple[float, float, float], side: str) -> tuple[float, float, float]:
    if side not in (BELOW, ABOVE):
        raise ValueError(f"side={side!r}; allowed: {BELOW}, {ABOVE}")
    point, low, high = interval
    if any(math.isnan(v) for v in interval) or not low <= high:
        raise ValueError(f"({point}, {low}, {high}) is not an estimate with its interval")
    return point, low, high


# --- the report's structure -----------------------------------------------------------------------
@dataclass
class Row:
    """One estimate of a part, against the paper's statement."""

    label: str
    paper: str
    ours: str
    outcome: str
    note: str = ""


@dataclass
class Part:
    """One statement of a claim, decided on its rows (R5)."""

    kind: str
    """DIRECTION or DETAIL (R6)."""
    name: str
    """A word or two: 'direction', 'size', 'example', ..."""
    statement: str
    """What the paper says, in plain words."""
    rule: str
    """The rule its rows are decided by: 'R1' ... 'R4'."""
    rows: list[Row] = field(default_factory=list)
    evidence: str = ""
    """The numbers behind the verdict, in a few words."""

    @property
    def verdict(self) -> str:
        return part_verdict([r.outcome for r in self.rows])

    def tally(self) -> str:
        """How the rows came out, e.g. '2 of 3 rows hold, 1 undecided'."""
        counts = {o: sum(r.outcome == o for r in self.rows) for o in OUTCOMES}
        n = len(self.rows)
        if n == 1:
            return f"the row {_verb(self.rows[0].outcome, 1)}"
        first, *rest = [(o, c) for o, c in counts.items() if c]
        text = f"{first[1]} of {n} rows {_verb(first[0], first[1])}"
        return ", ".join([text, *(f"{c} {_verb(o, c)}" for o, c in rest)])


def _verb(outcome: str, count: int) -> str:
    """'holds' / 'is absent' for one row, 'hold' / 'are absent' for several."""
    if outcome in (ABSENT, UNDECIDED):
        return f"{'is' if count == 1 else 'are'} {outcome}"
    if count == 1:
        return outcome
    return {HOLDS: "hold", OTHER_WAY: "hold the other way", SHORT: "fall short", FAILS: "do not hold"}[outcome]
