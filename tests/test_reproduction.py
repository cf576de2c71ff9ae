"""The reproduction report's statistics on known inputs, its claims on synthetic runs (which rows
count, the same runs once, each part decided by its rule), and the report built from the committed
paper-scale runs. The rules themselves: tests/test_verdicts.py."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mediated_transfer.reporting.intervals import (bootstrap, bootstrap_rows, format_interval, iqm, mean_curve_time,
                                                   probability_of_improvement, ratio_of_means, ratio_of_medians,
                                                   resample_indices, seeds_to_decide, sem)
from mediated_transfer.metrics import reward_loss, time_to_threshold, times_to_threshold_of_curves
from mediated_transfer.reporting.collect import CellRuns
from mediated_transfer.reporting.paper import paper_rows
from mediated_transfer.reporting.reproduction import (CLAIMS, Learner, claim_2, claim_5, claim_6, evaluate, headline, main,
                                                      same_runs, verdict_count)
from mediated_transfer.reporting.verdicts import (ABSENT, DIRECTION, FAILS, HOLDS, NOT_REPRODUCED, OTHER_WAY,
                                                  REPRODUCED, SHORT, UNDECIDED, VERDICTS, claim_verdict)
from mediated_transfer.results import RunResult

from .optional import needs_deep


def test_iqm_is_the_mean_of_the_middle_half():
    assert iqm([1, 2, 3, 4, 5, 6, 7, 100]) == pytest.approx(4.5)  # 3, 4, 5, 6
    assert iqm([5.0] * 4) == 5.0


def test_sem_is_the_sample_std_over_root_n_and_undefined_for_one_run():
    assert sem([2, 4, 4, 4, 5, 5, 7, 9]) == pytest.approx(2.138 / math.sqrt(8), abs=1e-3)  # sample std 2.138
    assert math.isnan(sem([3.0]))


def test_probability_of_improvement_counts_lower_as_better_and_ties_as_half():
    assert probability_of_improvement([1, 2], [3, 4]) == 1.0
    assert probability_of_improvement([3, 4], [1, 2]) == 0.0
    assert probability_of_improvement([1, 3], [2, 3]) == pytest.approx((1 + 1 + 0 + 0.5) / 4)  # 1<2, 1<3, 3>2, 3=3


def test_bootstrap_intervals_hold_their_point_and_rebuild_identically():
    rng = np.random.default_rng(3)
    a, b = rng.normal(50, 10, 20), rng.normal(100, 10, 20)
    point, low, high = ratio_of_means(a, b)
    assert low < point < high and point == pytest.approx(a.mean() / b.mean())
    assert ratio_of_means(a, b) == (point, low, high)  # seeded
    assert ratio_of_means([2.0] * 5, [4.0] * 5) == (0.5, 0.5, 0.5)
    # A wider spread gives a wider interval.
    wide = ratio_of_means(rng.normal(50, 40, 20), b)
    assert wide[2] - wide[1] > high - low
    with pytest.raises(ValueError, match="at least one run"):
        bootstrap(np.mean, [])


@pytest.mark.parametrize("sizes", [(20, 20), (19, 20), (7,), (1, 1), (3, 5, 3)])
def test_the_resample_matrix_draws_what_bootstraps_loop_draws(sizes):
    # bootstrap_rows draws groups of one size in one call; the intervals must stay the loop's.
    rng = np.random.default_rng(11)
    groups = [rng.normal(50, 20, n) for n in sizes]
    ratio = lambda *g: g[0].mean(axis=-1) / sum(x.mean(axis=-1) for x in g)  # noqa: E731
    assert bootstrap_rows(ratio, *groups, resamples=2000, seed=4) == bootstrap(
        lambda *g: float(ratio(*g)), *groups, resamples=2000, seed=4)
    assert resample_indices(sizes[0], 300, 4).tolist() == [
        list(r.integers(0, sizes[0], sizes[0])) for r in [np.random.default_rng(4)] for _ in range(300)]


def test_ratio_of_medians_takes_never_reached_as_slower_than_any():
    inf = math.inf
    assert ratio_of_medians([100, 100, 100], [200, 200, inf])[0] == 0.5
    assert ratio_of_medians([100, inf, inf], [200, 200, 200])[0] == math.inf


def test_an_interval_prints_its_bounds_and_says_when_one_is_infinite_or_undefined():
    assert format_interval((1.449, 1.262, 1.671)) == "1.45 [1.26, 1.67]"
    assert format_interval((0.5, 0.4, math.inf)) == "0.50 [0.40, ∞]"
    assert format_interval((math.nan, math.nan, math.nan)) == "n/a [n/a, n/a]"


def test_seeds_to_decide_follows_the_two_proportion_test():
    assert seeds_to_decide(0.1, 0.2) == 199  # the textbook value for 10 % vs 20 %
    assert seeds_to_decide(0.05, 0.05) is None
    assert seeds_to_decide(0.01, 0.02) > seeds_to_decide(0.1, 0.2)


STEPS = list(range(20_000, 500_001, 20_000))


def _run(cell: str, seed: int, reached_at: int | None, wobble: float = 0.0) -> RunResult:
    """A synthetic run whose <R> is 2 before ``reached_at`` and 9.5 (+ wobble) from it on; None: never."""
    curve = [9.5 + wobble if reached_at is not None and s >= reached_at else 2.0 for s in STEPS]
    strategy, n = cell.rsplit("_", 1)
    return RunResult(algorithm="x", representation="x", strategy=strategy, n_source=int(n), seed=seed,
                     budget=500_000, steps=STEPS, mean_reward=curve, success_rate=[r / 10 for r in curve],
                     reward_loss=reward_loss(curve), time_to_threshold=time_to_threshold(STEPS, curve),
                     source_phase_end=None, source_tasks_solved=0, wall_time_s=1.0, learning_steps_per_s=1.0)


def _learner(table: str, reached: dict[str, list[int | None]], wobble: dict[str, float] | None = None) -> Learner:
    """A table of synthetic runs: per row, each run's first step at the threshold."""
    wobble = wobble or {}
    cells = {cell: CellRuns(cell.rsplit("_", 1)[0], int(cell.rsplit("_", 1)[1]),
                            [_run(cell, seed, at, wobble.get(cell, 0.0)) for seed, at in enumerate(times)])
             for cell, times in reached.items()}
    return Learner(table, {"II": "RBF", "III": "FSR", "IV": "DNN"}[table], cells, {r.cell: r for r in paper_rows(table)})


TRANSFER = [f"{s}_{n}" for s in ("regular", "scaffolded") for n in (1, 15, 50, 100, 5000)]


def test_claim_6_decides_each_part_on_the_rows_the_paper_names():
    # As the paper has it: scaffolded 15 slower than regular 100 (160k against 80k), regular 50
    # never learns in 15 of 20 runs, no scaffolded run fails.
    reached = {c: [80_000] * 20 for c in TRANSFER} | {"none_0": [80_000] * 20, "scaffolded_15": [160_000] * 20,
                                                      "regular_50": [None] * 15 + [80_000] * 5}
    claim = claim_6({"IV": _learner("IV", reached)})
    outcomes = {p.name: [r.outcome for r in p.rows] for p in claim.parts}
    assert outcomes == {"slower": [HOLDS], "size": [HOLDS], "more robust": [HOLDS], "example": [HOLDS, HOLDS]}
    assert claim.verdict == REPRODUCED

    # The same rows, but scaffolding fails more often and is not slower: the robustness the other
    # way, "slower" absent, the example fails.
    reached = {c: [80_000] * 20 for c in TRANSFER} | {"none_0": [80_000] * 20,
                                                      "scaffolded_50": [None] * 15 + [80_000] * 5}
    claim = claim_6({"IV": _learner("IV", reached)})
    outcomes = {p.name: [r.outcome for r in p.rows] for p in claim.parts}
    assert outcomes == {"slower": [ABSENT], "size": [SHORT], "more robust": [OTHER_WAY], "example": [FAILS, FAILS]}
    assert claim.verdict == NOT_REPRODUCED


def test_claim_6_robustness_is_absent_not_undecided_when_the_estimate_points_against_the_paper():
    # One scaffolded failure in 100 against none: absent (R1), whatever a power calculation says (R8).
    reached = {c: [80_000] * 20 for c in TRANSFER} | {"none_0": [80_000] * 20,
                                                      "scaffolded_50": [None] + [80_000] * 19}
    robust = next(p for p in claim_6({"IV": _learner("IV", reached)}).parts if p.name == "more robust")
    assert [r.outcome for r in robust.rows] == [ABSENT] and robust.verdict == NOT_REPRODUCED
    assert "would need about" in robust.rows[0].note


def test_the_times_to_threshold_of_many_curves_are_each_curves_time_to_threshold():
    rng = np.random.default_rng(5)
    curves = np.vstack([rng.uniform(6, 10, (2_000, 25)), np.full((1, 25), 9.0), np.full((1, 25), 2.0),
                        np.r_[np.full(24, 9.0), 7.0][None, :], np.r_[7.0, np.full(24, 8.0 - 1e-12)][None, :]])
    each = [time_to_threshold(STEPS, c) for c in curves]
    assert times_to_threshold_of_curves(STEPS, curves).tolist() == [math.inf if t is None else t for t in each]


def test_the_mean_curves_bootstrap_reads_every_resample_as_the_mean_curve_is_read():
    rng = np.random.default_rng(7)
    curves = np.clip(np.linspace(2, 9.5, 25) + rng.normal(0, 1.5, (20, 25)), 0, 10)
    curves[:4] = 2.0  # 4 of 20 runs never learn
    found = mean_curve_time(curves, STEPS)
    picks = resample_indices(20)
    each = [time_to_threshold(STEPS, curves[i].mean(axis=0)) for i in picks]
    assert found.share_reaching == pytest.approx(np.mean([t is not None for t in each]))
    point = time_to_threshold(STEPS, curves.mean(axis=0))
    assert found.interval[0] == (math.inf if point is None else point)
    assert mean_curve_time(curves, STEPS) == found  # seeded
    # the resamples are bootstrap's own: the same seed draws the same runs
    values = rng.normal(size=20)
    assert bootstrap(np.mean, values)[1:] == tuple(np.quantile(values[picks].mean(axis=1), [0.025, 0.975]))
    # rows every resample agrees on
    assert mean_curve_time(np.full((20, 25), 9.0), STEPS) == mean_curve_time(np.full((3, 25), 9.0), STEPS)
    assert mean_curve_time(np.full((20, 25), 9.0), STEPS).share_reaching == 1.0
    never = mean_curve_time(np.full((20, 25), 2.0), STEPS)
    assert never.share_reaching == 0.0 and never.interval == (math.inf, math.inf, math.inf)
    with pytest.raises(ValueError, match="non-empty"):
        mean_curve_time(np.empty((0, 25)), STEPS)


def test_claim_5_reads_the_mean_curve_with_its_bootstrap():
    # 4 of 20 runs without transfer never learn (the case) or 5: the mean curve ends at the
    # threshold (9.5 - 4 x 7.5 / 20 = 8.0) or just below it (7.625: never), and resamples go either
    # way: undecided, whichever way the mean curve itself falls (R3). 16 of 20: never, decided.
    for never, outcome in ((5, UNDECIDED), (4, UNDECIDED), (16, HOLDS), (0, FAILS)):
        reached = {"none_0": [None] * never + [80_000] * (20 - never), "regular_100": [80_000] * 20}
        reach = claim_5({"IV": _learner("IV", reached)}).parts[0]
        assert [r.outcome for r in reach.rows] == [outcome, HOLDS], never
        assert "% of resamples" in reach.rows[0].ours


def test_claim_2_counts_the_same_runs_once_and_only_the_linear_learners():
    base = {"none_0": [300_000] * 20}
    same = _learner("II", base | {"regular_1": [100_000] * 20, "scaffolded_1": [100_000] * 20})
    other = _learner("III", base | {"regular_1": [100_000] * 20, "scaffolded_1": [100_000] * 20},
                     wobble={"scaffolded_1": 0.1})  # other curves: not the same runs
    dnn = _learner("IV", base | {"regular_1": [400_000] * 20, "scaffolded_1": [400_000] * 20})
    assert same_runs(same, "regular_1", "scaffolded_1") == (20, 20)
    assert same_runs(other, "regular_1", "scaffolded_1") == (0, 20)
    claim = claim_2({"II": same, "III": other, "IV": dnn})
    labels = [r.label for r in claim.parts[0].rows]
    assert sum("RBF regular_1 = scaffolded_1" in label for label in labels) == 2  # L_R and time, once
    assert sum(label.startswith("FSR") for label in labels) == 4  # two rows of other runs, twice
    assert not any(label.startswith("DNN") for label in labels)  # outside the claim: shown only
    assert any("| DNN |" in line for line in claim.shown)
    assert claim.verdict == REPRODUCED


@pytest.mark.slow
def test_a_claims_verdict_is_derived_from_its_parts_and_each_has_a_direction():
    from mediated_transfer.config.compose import CONF_DIR
    from mediated_transfer.reporting.reproduction import load

    claims = evaluate(load(CONF_DIR.parent))
    assert len(claims) == len(CLAIMS) == 6
    for claim in claims:
        assert any(p.kind == DIRECTION for p in claim.parts)
        assert claim.verdict == claim_verdict([(p.kind, p.verdict) for p in claim.parts])
        assert claim.source.startswith(("Sec. VI", "abstract")) and claim.scope
        assert all(p.rows for p in claim.parts), claim.text
        assert claim.sentence().startswith(claim.verdict.capitalize() + ".")
    counted = {r.label for c in claims for p in c.parts for r in p.rows}
    assert "RBF regular_1 = scaffolded_1 / none_0, mean L_R" in counted  # the same runs, once
    assert not any(label.startswith(("DNN regular_1 ", "DNN scaffolded_1 ")) for label in counted)  # out of claim 2
    assert verdict_count(claims).count(",") == len(VERDICTS) - 1


@pytest.mark.slow
@needs_deep  # whether the DNN's runs are current is read from the DQN's code, which imports torch
def test_the_report_gives_a_verdict_on_each_claim_from_the_committed_runs(tmp_path):
    from mediated_transfer.config.compose import CONF_DIR

    out = tmp_path / "REPRODUCTION.md"
    assert main(["--root", str(CONF_DIR.parent), "--out", str(out)]) == 0
    text = out.read_text()
    for i in range(1, len(CLAIMS) + 1):
        assert f"### Claim {i}: " in text
    verdicts = [line.split("**")[1] for line in text.split("## How a verdict")[0].splitlines()
                if line.startswith("| ") and "**" in line]
    assert len(verdicts) == len(CLAIMS)
    assert set(verdicts) <= set(VERDICTS)
    assert "## Summary" in text and "**What was hard.**" in text and "**What differs from the paper's setup.**" in text
    assert "**R1, direction.**" in text  # the rules, printed where they are applied
    assert "RBF 220 of 220 runs, FSR 220 of 220 runs" in text  # Tables II and III are complete
    # the DQN's failures point at the study of their cause, and the link resolves beside the report
    assert "(dqn_failure_ablation.md)" in text
    assert (CONF_DIR.parent / "reports" / "dqn_failure_ablation.md").is_file()


@pytest.mark.slow
@needs_deep
def test_the_readmes_headline_is_the_one_the_committed_runs_give():
    from mediated_transfer.config.compose import CONF_DIR
    from mediated_transfer.reporting.reproduction import load, with_headline
    from mediated_transfer.reporting.reproduction.open_question import read

    root = CONF_DIR.parent
    readme = (root / "README.md").read_text()
    assert with_headline(readme, headline(load(root), question=read(root))) == readme, (
        "README's headline is stale: run `make reproduction` after committing runs")
    with pytest.raises(ValueError, match="no headline markers"):
        with_headline("# no markers", "x")


def test_an_interval_over_runs_that_never_reach_the_threshold_ends_at_never():
    from mediated_transfer.reporting.intervals import median

    times = [80_000, 100_000, 120_000, math.inf, math.inf, math.inf, math.inf]
    point, low, high = bootstrap(median, times)
    assert point == math.inf and high == math.inf and low < math.inf  # 4 of 7 never: the median is never
    assert not any(math.isnan(v) for v in (point, low, high))
