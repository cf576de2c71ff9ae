"""Every branch of every verdict rule (reporting/verdicts.py, RULES R1-R6) on synthetic numbers: a row
that holds, holds the other way, is absent or undecided; a part and a claim from them. The report
prints RULES; these tests keep the code to the text."""

from __future__ import annotations

import math

import pytest

from mediated_transfer.reporting.verdicts import (ABOVE, ABSENT, BELOW, DETAIL, DIRECTION, FAILS, HOLDS,
                                                  NOT_REPRODUCED, OTHER_WAY, PARTLY, REPRODUCED, RULES, SHORT,
                                                  UNDECIDED, Part, Row, claim_verdict, direction, not_learned_at_all,
                                                  part_verdict, reaches_threshold, size)


# --- R1 -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("interval, side, outcome", [
    ((0.5, 0.3, 0.8), BELOW, HOLDS),          # faster, the interval below 1
    ((1.5, 1.2, 1.9), BELOW, OTHER_WAY),      # slower, the interval above 1
    ((0.8, 0.5, 1.3), BELOW, UNDECIDED),      # points the claim's way, the interval includes 1
    ((1.1, 0.7, 1.6), BELOW, ABSENT),         # points against the claim, the interval includes 1
    ((1.0, 0.8, 1.25), BELOW, ABSENT),        # no difference at all
    ((1.0, 1.0, 1.25), BELOW, ABSENT),        # the interval touches 1: it includes it
    ((2.1, 1.7, 2.7), ABOVE, HOLDS),          # the claim says above 1: worse L_R
    ((0.6, 0.4, 0.9), ABOVE, OTHER_WAY),
    ((1.4, 0.8, 3.0), ABOVE, UNDECIDED),
    ((1.0, 0.75, 1.33), ABOVE, ABSENT),
    ((0.9, 0.7, 1.2), ABOVE, ABSENT),
])
def test_r1_a_ratio(interval, side, outcome):
    assert direction(interval, side) == outcome


@pytest.mark.parametrize("interval, outcome", [
    ((-0.2, -0.35, -0.05), HOLDS),            # fewer failures with the claim's strategy
    ((0.2, 0.05, 0.35), OTHER_WAY),
    ((-0.05, -0.15, 0.05), UNDECIDED),
    ((0.01, 0.0, 0.03), ABSENT),              # 1 of 100 against 0 of 100: the claim said fewer
    ((0.0, 0.0, 0.0), ABSENT),
])
def test_r1_a_difference_of_shares_has_no_difference_at_zero(interval, outcome):
    assert direction(interval, BELOW, null=0.0) == outcome


def test_r1_refuses_what_is_not_an_estimate():
    with pytest.raises(ValueError, match="side"):
        direction((0.5, 0.3, 0.8), "faster")
    with pytest.raises(ValueError, match="not an estimate"):
        direction((0.5, 0.8, 0.3), BELOW)
    with pytest.raises(ValueError, match="not an estimate"):
        direction((math.nan, 0.3, 0.8), BELOW)


def test_r1_an_interval_that_ends_at_never_is_still_an_interval():
    assert direction((math.inf, 1.2, math.inf), ABOVE) == HOLDS
    assert direction((0.5, 0.3, math.inf), BELOW) == UNDECIDED


# --- R2 -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("interval, paper, side, outcome", [
    ((0.3, 0.15, 0.6), 0.2, BELOW, HOLDS),     # the interval includes the paper's factor
    ((0.1, 0.05, 0.15), 0.2, BELOW, HOLDS),    # a larger effect than the paper's: beyond it
    ((0.5, 0.3, 0.8), 0.2, BELOW, SHORT),      # faster, but not by the paper's factor
    ((1.15, 0.71, 2.3), 0.67, BELOW, SHORT),   # short of the factor though the direction is absent
    ((0.9, 0.55, 1.4), 0.67, BELOW, UNDECIDED),  # includes both the factor and 1
    ((2.0, 1.6, 2.6), 2.2, ABOVE, HOLDS),
    ((3.0, 2.5, 3.5), 2.2, ABOVE, HOLDS),
    ((1.0, 0.75, 1.33), 1.41, ABOVE, SHORT),
    ((1.3, 0.9, 1.6), 1.41, ABOVE, UNDECIDED),
])
def test_r2_a_factor(interval, paper, side, outcome):
    assert size(interval, paper, side) == outcome


@pytest.mark.parametrize("interval, paper, side, outcome", [
    ((7.83, 5.90, 9.33), 5.0, BELOW, SHORT),          # the paper: only ~5 without transfer
    ((5.2, 4.1, 6.3), 5.0, BELOW, HOLDS),
    ((3.0, 2.0, 4.0), 5.0, BELOW, HOLDS),
    ((9.76, 9.63, 9.87), 9.0, ABOVE, HOLDS),          # the paper: ~9 with transfer
    ((8.0, 7.5, 8.5), 9.0, ABOVE, SHORT),
    ((80e3, 60e3, 80e3), 220e3, BELOW, HOLDS),        # reached by ~220k: sooner is beyond
    ((300e3, 260e3, 340e3), 220e3, BELOW, SHORT),
])
def test_r2_a_value_without_a_no_difference_is_never_undecided(interval, paper, side, outcome):
    assert size(interval, paper, side, null=None) == outcome


# --- R3, R4 -------------------------------------------------------------------------------------
@pytest.mark.parametrize("share, paper, outcome", [
    (1.0, True, HOLDS),          # every resample's mean curve reaches it, as the paper says
    (0.975, True, HOLDS),        # at least 97.5 %: the boundary holds
    (0.9749, True, UNDECIDED),   # just short of it
    (0.58, True, UNDECIDED),
    (0.0251, True, UNDECIDED),
    (0.025, True, FAILS),        # never in at least 97.5 % of resamples: the opposite holds
    (0.0, True, FAILS),
    (0.0, False, HOLDS),         # the paper says never: never in every resample
    (0.025, False, HOLDS),       # never in 97.5 % (250 of 10,000 resamples reach it)
    (0.0251, False, UNDECIDED),
    (0.42, False, UNDECIDED),    # the case: the mean curve never, yet it reaches in 42 %
    (0.9749, False, UNDECIDED),
    (0.975, False, FAILS),       # reaches in at least 97.5 % though the paper says never
    (1.0, False, FAILS),
])
def test_r3_reaching_the_threshold_as_the_paper_says_in_at_least_97_5_percent_of_resamples(share, paper, outcome):
    assert reaches_threshold(share, paper) == outcome


def test_r3_a_count_of_resamples_on_the_boundary_decides_despite_round_off():
    assert reaches_threshold(9_750 / 10_000, True) == HOLDS
    assert reaches_threshold(250 / 10_000, False) == HOLDS
    assert reaches_threshold(1 - 9_750 / 10_000, False) == HOLDS
    assert reaches_threshold(251 / 10_000, False) == UNDECIDED
    assert reaches_threshold(9_749 / 10_000, True) == UNDECIDED


@pytest.mark.parametrize("share", [-0.1, 1.1, math.nan])
def test_r3_refuses_what_is_not_a_share(share):
    with pytest.raises(ValueError, match="not a share"):
        reaches_threshold(share, True)


@pytest.mark.parametrize("never, runs, outcome", [
    (20, 20, HOLDS), (11, 20, HOLDS), (10, 20, FAILS), (5, 20, FAILS), (0, 20, FAILS)])
def test_r4_not_learned_at_all_needs_more_than_half_the_runs(never, runs, outcome):
    assert not_learned_at_all(never, runs) == outcome


def test_r4_refuses_counts_that_are_not_counts():
    with pytest.raises(ValueError, match="not a count"):
        not_learned_at_all(21, 20)
    with pytest.raises(ValueError, match="not a count"):
        not_learned_at_all(0, 0)


# --- R5 -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("outcomes, verdict", [
    ([HOLDS, HOLDS], REPRODUCED),
    ([HOLDS], REPRODUCED),
    ([HOLDS, OTHER_WAY], NOT_REPRODUCED),        # a row against outweighs one that holds
    ([HOLDS, SHORT], NOT_REPRODUCED),
    ([HOLDS, FAILS], NOT_REPRODUCED),
    ([ABSENT, ABSENT], NOT_REPRODUCED),          # every row shows no difference
    ([ABSENT, UNDECIDED], UNDECIDED),
    ([UNDECIDED], UNDECIDED),
    ([HOLDS, UNDECIDED], PARTLY),
    ([HOLDS, ABSENT], PARTLY),
    ([UNDECIDED, UNDECIDED, SHORT], NOT_REPRODUCED),
    ([], UNDECIDED),
])
def test_r5_a_part_from_its_rows(outcomes, verdict):
    assert part_verdict(outcomes) == verdict


def test_r5_refuses_an_unknown_outcome():
    with pytest.raises(ValueError, match="unknown outcomes"):
        part_verdict(["reproduced"])


# --- R6 -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("parts, verdict", [
    ([(DIRECTION, REPRODUCED), (DETAIL, REPRODUCED)], REPRODUCED),
    ([(DIRECTION, REPRODUCED), (DETAIL, NOT_REPRODUCED)], PARTLY),       # direction yes, size no
    ([(DIRECTION, PARTLY), (DETAIL, NOT_REPRODUCED)], PARTLY),
    ([(DIRECTION, REPRODUCED), (DETAIL, UNDECIDED)], PARTLY),
    ([(DIRECTION, NOT_REPRODUCED), (DIRECTION, REPRODUCED)], PARTLY),    # one of two directions
    ([(DIRECTION, NOT_REPRODUCED), (DETAIL, REPRODUCED)], NOT_REPRODUCED),  # an example alone does not carry it
    ([(DIRECTION, UNDECIDED), (DETAIL, NOT_REPRODUCED)], NOT_REPRODUCED),
    ([(DIRECTION, NOT_REPRODUCED)], NOT_REPRODUCED),
    ([(DIRECTION, UNDECIDED), (DETAIL, UNDECIDED)], UNDECIDED),
    ([(DIRECTION, UNDECIDED), (DETAIL, REPRODUCED)], UNDECIDED),
])
def test_r6_a_claim_from_its_parts(parts, verdict):
    assert claim_verdict(parts) == verdict


def test_r6_refuses_a_claim_without_a_direction_or_with_unknown_parts():
    with pytest.raises(ValueError, match="direction part"):
        claim_verdict([(DETAIL, REPRODUCED)])
    with pytest.raises(ValueError, match="not \\(size, reproduced\\)"):
        claim_verdict([("size", REPRODUCED)])


# --- the text and the code ----------------------------------------------------------------------------
def test_the_rules_text_names_every_outcome_and_verdict_the_code_gives():
    for word in (HOLDS, OTHER_WAY, ABSENT, UNDECIDED, SHORT, FAILS, REPRODUCED, PARTLY, NOT_REPRODUCED):
        assert f"**{word}**" in RULES, word
    for rule in ("R1", "R2", "R3", "R4", "R5", "R6", "R7", "R8"):
        assert f"**{rule}," in RULES


def test_a_part_tallies_its_rows_in_words():
    part = Part(DIRECTION, "direction", "transfer is faster", "R1",
                [Row("a", "", "", HOLDS), Row("b", "", "", HOLDS), Row("c", "", "", UNDECIDED)])
    assert part.tally() == "2 of 3 rows hold, 1 is undecided"
    assert part.verdict == PARTLY
    part.rows = [Row("a", "", "", ABSENT)]
    assert part.tally() == "the row is absent" and part.verdict == NOT_REPRODUCED
