"""Reward loss and time to threshold (Sec. IV-C) on hand-made curves."""

import math

import numpy as np
import pytest

from mediated_transfer.metrics import (
    MetricsConfig,
    first_point_at_threshold,
    learning_span,
    loss_after_learning,
    median_time,
    reward_loss,
    summarise_runs,
    time_to_threshold,
)

STEPS = [20_000, 40_000, 60_000, 80_000, 100_000]


def test_reward_loss_sums_the_gap_to_the_maximum_reward():
    assert reward_loss([10.0] * 25) == 0.0
    assert reward_loss([0.0] * 25) == 250.0
    assert reward_loss([2.0, 5.0, 8.0, 10.0]) == pytest.approx(8 + 5 + 2 + 0)
    assert reward_loss([0.5, 1.0], max_reward=1.0) == pytest.approx(0.5)


@pytest.mark.parametrize("curve", [[80.0, 90.0], [-1.0, 5.0], [5.0, float("nan")], []])
def test_reward_loss_rejects_curves_that_are_not_mean_rewards(curve):
    with pytest.raises(ValueError, match="mean_rewards"):
        reward_loss(curve)


def test_time_to_threshold_is_the_first_point_of_the_final_stretch_above():
    assert time_to_threshold(STEPS, [2.0, 6.0, 8.0, 9.0, 9.5]) == 60_000
    # At the threshold counts as reached.
    assert time_to_threshold(STEPS, [8.0] * 5) == 20_000


def test_time_to_threshold_ignores_an_early_crossing_followed_by_a_dip():
    # Above at 40k, dips below at 60k, then stays above from 80k: "stable" from 80k.
    assert time_to_threshold(STEPS, [3.0, 8.5, 7.9, 8.2, 9.0]) == 80_000


def test_time_to_threshold_is_none_when_never_reached_or_below_at_the_end():
    assert time_to_threshold(STEPS, [1.0, 2.0, 4.0, 6.0, 7.99]) is None
    assert time_to_threshold(STEPS, [8.0, 9.0, 9.5, 9.0, 7.5]) is None


def test_first_point_at_threshold_counts_a_crossing_even_if_the_curve_dips_later():
    assert first_point_at_threshold([1.0, 8.0, 2.0, 9.0, 9.0], 8.0) == 1
    assert first_point_at_threshold([1.0, 7.9, 2.0], 8.0) is None


def test_learning_span_runs_from_discovery_to_the_first_point_at_the_threshold():
    curve = [0.0, 2.0, 8.5, 3.0, 9.0]
    assert learning_span(25_000, STEPS, curve, 8.0) == 60_000 - 25_000
    # The threshold passed at an evaluation before the first rewarded episode of learning
    # (a transferred skill): no negative span.
    assert learning_span(70_000, STEPS, curve, 8.0) == 0
    assert learning_span(None, STEPS, curve, 8.0) is None  # never rewarded on a target task
    assert learning_span(25_000, STEPS, [0.0, 7.9, 0.0, 0.0, 0.0], 8.0) is None  # never reached


def test_loss_after_learning_is_the_reward_loss_from_the_first_point_at_the_threshold():
    assert loss_after_learning([0.0, 9.0, 7.0, 10.0], 8.0, 10.0) == 1.0 + 3.0 + 0.0  # from 9.0 on
    assert loss_after_learning([0.0, 7.9, 0.0], 8.0, 10.0) is None  # never learned


def test_medians_count_a_never_as_slower_than_any_value():
    assert median_time([100, None, 300]) == 300
    assert median_time([None, None, 100]) is None


def test_time_to_threshold_tolerates_round_off_of_averaging_only():
    # 20 runs' <R> (multiples of 0.1, 100 episodes each) whose exact mean is 8: averaged over
    # runs in floats it comes out as 7.999999999999998.
    runs = [6.7, 9.0, 9.7, 6.1, 7.4, 8.5, 6.4, 8.0, 8.5, 9.0,
            9.7, 7.6, 7.7, 7.8, 9.8, 6.7, 7.9, 6.1, 7.7, 9.7]
    summary = summarise_runs(np.tile(np.array(runs)[:, None], (1, 5)), STEPS)
    assert summary["mean_curve"][0] < 8.0
    assert summary["time_to_threshold"] == 20_000
    assert time_to_threshold(STEPS, [8.0 - 1e-12] * 5) == 20_000
    assert time_to_threshold(STEPS, [8.0 - 1e-6] * 5) is None


def test_time_to_threshold_rejects_mismatched_or_unordered_steps():
    with pytest.raises(ValueError, match="same length"):
        time_to_threshold(STEPS[:-1], [9.0] * 5)
    with pytest.raises(ValueError, match="strictly increasing"):
        time_to_threshold([0, 20, 20, 40, 60], [9.0] * 5)


def test_summarise_runs_gives_mean_sem_reward_loss_and_both_times():
    curves = np.array(
        [
            [2.0, 8.0, 9.0, 10.0, 10.0],  # reaches at 40k, L_R = 8+2+1 = 11
            [0.0, 4.0, 8.0, 9.0, 10.0],  # reaches at 60k, L_R = 10+6+2+1 = 19
            [0.0, 2.0, 5.0, 6.0, 7.0],  # never reaches,   L_R = 10+8+5+4+3 = 30
        ]
    )
    summary = summarise_runs(curves, STEPS)
    assert summary["n_runs"] == 3
    np.testing.assert_allclose(summary["mean_curve"], [2 / 3, 14 / 3, 22 / 3, 25 / 3, 9.0])
    np.testing.assert_allclose(summary["sem_curve"], curves.std(axis=0, ddof=1) / math.sqrt(3))
    np.testing.assert_allclose(summary["reward_loss"], [11.0, 19.0, 30.0])
    assert summary["reward_loss_mean"] == pytest.approx(20.0)
    assert summary["reward_loss_sem"] == pytest.approx(np.std([11, 19, 30], ddof=1) / math.sqrt(3))
    # L_R is linear: the mean curve's loss is the mean of the runs' losses.
    assert reward_loss(summary["mean_curve"]) == pytest.approx(summary["reward_loss_mean"])
    # The mean curve crosses 8 only at 80k (25/3); the runs' median is 60k (inf counts last).
    assert summary["time_to_threshold"] == 80_000
    assert summary["time_to_threshold_runs"] == [40_000, 60_000, None]
    assert summary["runs_reaching_threshold"] == 2
    assert summary["time_to_threshold_median"] == 60_000
    assert summary["final_reward_mean"] == pytest.approx(9.0)


def test_median_time_is_none_when_half_the_runs_never_reach_the_threshold():
    curves = np.array([[9.0] * 5, [1.0] * 5])
    summary = summarise_runs(curves, STEPS)
    assert summary["time_to_threshold_runs"] == [20_000, None]
    assert summary["time_to_threshold_median"] is None
    # ... while an even number of reaching runs averages the two middle ones.
    curves = np.array([[9.0] * 5, [1.0, 9.0, 9.0, 9.0, 9.0]])
    assert summarise_runs(curves, STEPS)["time_to_threshold_median"] == 30_000


def test_a_single_run_has_an_undefined_standard_error():
    summary = summarise_runs(np.array([[2.0, 8.0, 9.0, 10.0, 10.0]]), STEPS)
    assert summary["reward_loss_mean"] == pytest.approx(11.0)
    assert math.isnan(summary["reward_loss_sem"])
    assert np.all(np.isnan(summary["sem_curve"]))


def test_summarise_runs_uses_the_configured_threshold():
    curves = np.array([[2.0, 6.0, 7.0, 7.0, 7.0]])
    assert summarise_runs(curves, STEPS)["time_to_threshold"] is None
    assert summarise_runs(curves, STEPS, MetricsConfig(threshold=6.0))["time_to_threshold"] == 40_000


def test_summarise_runs_rejects_bad_shapes_and_configs():
    with pytest.raises(ValueError, match="runs x evaluation points"):
        summarise_runs(np.array([9.0] * 5), STEPS)
    with pytest.raises(ValueError, match="evaluation points"):
        summarise_runs(np.ones((2, 4)), STEPS)
    with pytest.raises(ValueError, match="metrics.threshold"):
        MetricsConfig(threshold=12.0)
