"""The reproduction report's statistics on known inputs, its verdict rules, and the report
built from the committed paper-scale runs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mediated_transfer.reporting.intervals import (bootstrap, format_interval, iqm, probability_of_improvement,
                                                   ratio_of_means, ratio_of_medians, seeds_to_decide, sem)
from mediated_transfer.reporting.reproduction import CLAIMS, combine, main, row_verdict


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


@pytest.mark.parametrize("ratio,paper,verdict", [
    ((0.5, 0.3, 0.8), 0.2, "partly"),        # faster, but not by the paper's factor
    ((0.3, 0.15, 0.6), 0.2, "reproduced"),   # the interval reaches the paper's factor
    ((0.5, 0.3, 0.8), None, "reproduced"),   # no factor claimed
    ((0.8, 0.5, 1.3), None, "undecided"),
    ((1.1, 0.7, 1.6), None, "absent"),
    ((1.5, 1.2, 1.9), None, "against"),
])
def test_a_rows_verdict(ratio, paper, verdict):
    assert row_verdict(ratio, paper) == verdict


def test_a_claims_verdict_from_its_rows():
    assert combine(["reproduced", "reproduced"]) == "reproduced"
    assert combine(["reproduced", "undecided"]) == "partly"
    assert combine(["partly", "against"]) == "not reproduced"
    assert combine(["undecided", "absent"]) == "undecided"
    assert combine(["absent", "absent"]) == "not reproduced"
    assert combine([]) == "undecided"


def test_the_report_gives_a_verdict_on_each_claim_from_the_committed_runs(tmp_path):
    from mediated_transfer.config.compose import CONF_DIR

    out = tmp_path / "REPRODUCTION.md"
    assert main(["--root", str(CONF_DIR.parent), "--out", str(out)]) == 0
    text = out.read_text()
    for i in range(1, len(CLAIMS) + 1):
        assert f"### Claim {i}: " in text
    verdicts = [line.split("**")[1] for line in text.splitlines() if line.startswith("| ") and "**" in line]
    assert len(verdicts) == len(CLAIMS)
    assert set(verdicts) <= {"reproduced", "partly", "not reproduced", "undecided"}
    assert "RBF 220 of 220, FSR 220 of 220" in text  # Tables II and III are complete
    # the DQN's failures point at the study of their cause, and the link resolves beside the report
    assert "(dqn_failure_ablation.md)" in text
    assert (CONF_DIR.parent / "reports" / "dqn_failure_ablation.md").is_file()


def test_the_readmes_headline_is_the_one_the_committed_runs_give():
    from mediated_transfer.config.compose import CONF_DIR
    from mediated_transfer.reporting.reproduction import headline, load, with_headline

    root = CONF_DIR.parent
    readme = (root / "README.md").read_text()
    assert with_headline(readme, headline(load(root))) == readme, (
        "README's headline is stale: run `make reproduction` after committing runs")
    with pytest.raises(ValueError, match="no headline markers"):
        with_headline("# no markers", "x")


def test_an_interval_over_runs_that_never_reach_the_threshold_ends_at_never():
    from mediated_transfer.reporting.intervals import median

    times = [80_000, 100_000, 120_000, math.inf, math.inf, math.inf, math.inf]
    point, low, high = bootstrap(median, times)
    assert point == math.inf and high == math.inf and low < math.inf  # 4 of 7 never: the median is never
    assert not any(math.isnan(v) for v in (point, low, high))
