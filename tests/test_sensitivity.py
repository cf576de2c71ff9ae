"""Issue 13's sensitivity study: its measures on known runs, and the study end to end at smoke
scale (sweep, then report)."""

from __future__ import annotations

import numpy as np
import pytest

from mediated_transfer.results import RunResult
from mediated_transfer.sensitivity.measures import Measures, arm_gain, ratio_interval, threshold_time

STEPS = [100, 200, 300, 400]
FAST = Measures(resamples=500)


def _run(curve, first_reward=None, seed=0, cell=("none", 0)) -> RunResult:
    loss = sum(10 - r for r in curve)
    return RunResult("linear_q", "rbf", cell[0], cell[1], seed, 400, STEPS, list(curve),
                     [r / 10 for r in curve], loss, None, None, 0, 1.0, 1.0,
                     first_target_reward_step=first_reward)


def test_learning_span_runs_from_the_first_reward_to_the_first_point_at_the_threshold():
    assert _run([0, 9, 2, 9], first_reward=150).learning_span(8.0) == 50
    # Reaching the threshold at the point where the reward came counts from the reward.
    assert _run([8, 9, 9, 9], first_reward=120).learning_span(8.0) == 0
    assert _run([0, 7.9, 0, 0], first_reward=150).learning_span(8.0) is None  # never reached
    assert _run([0, 0, 0, 0]).learning_span(8.0) is None  # never rewarded


def test_threshold_time_is_the_papers_and_the_budget_when_never_reached():
    curves = np.array([[0, 9, 9, 9], [0, 7, 9, 9]], dtype=float)  # mean 0, 8, 9, 9
    assert threshold_time(curves, STEPS, 8.0, 500) == 200
    assert threshold_time(curves[:, ::-1], STEPS, 8.0, 500) == 500


def test_ratio_interval_is_the_ratio_of_means_with_an_interval_around_it():
    rng = np.random.default_rng(1)
    arm, none = rng.normal(60, 8, 10), rng.normal(110, 12, 10)
    interval = ratio_interval(arm, none, np.mean, FAST)
    assert interval.value == pytest.approx(arm.mean() / none.mean())
    assert interval.low < interval.value < interval.high
    assert 0.4 < interval.low and interval.high < 0.75
    # Deterministic: the same data give the same interval.
    assert ratio_interval(arm, none, np.mean, FAST) == interval
    # Every resample equal: BCa is undefined, the percentile interval is the point.
    same = ratio_interval(np.full(5, 3.0), np.full(5, 6.0), np.mean, FAST)
    assert (same.value, same.low, same.high) == (0.5, 0.5, 0.5)


def test_arm_gain_compares_a_transfer_arm_with_its_worlds_runs_without_transfer():
    none = [_run([0, 0, 9, 9], seed=s) for s in range(4)]
    arm = [_run([9, 9, 9, 9], seed=s, cell=("regular", 50)) for s in range(4)]
    gain = arm_gain("regular_50", arm, none, 8.0, 400, FAST)
    assert gain.reward_loss_ratio.value == pytest.approx(4 / 22)
    assert (gain.threshold_time, gain.threshold_reached) == (100, True)
    assert gain.threshold_time_ratio.value == pytest.approx(100 / 300)
    never = [_run([0, 0, 0, 0], seed=s, cell=("regular", 50)) for s in range(4)]
    gain = arm_gain("regular_50", never, none, 8.0, 400, FAST)
    assert (gain.threshold_time, gain.threshold_reached) == (400, False)  # the budget: a bound


@pytest.mark.slow
def test_the_study_sweeps_and_reports_end_to_end(tmp_path):
    """Two worlds x the study's three arms x one seed at smoke scale: the sweep puts each world's
    runs in its own folder, and the report has a row per world with both gains."""
    from mediated_transfer.sensitivity.__main__ import main as sensitivity_main

    from .test_sweep import _run_cli
    from .test_tracking import fresh_store

    fresh_store(tmp_path)
    common = ["scale=smoke", f"paths.root={tmp_path}", "env=default,tool_frame", "seed=0,1"]
    _run_cli("experiment=sensitivity", "hydra/launcher=basic", *common)
    sweep = tmp_path / "multirun" / "sensitivity" / "smoke"
    found = sorted(p.parent.relative_to(sweep).as_posix() for p in sweep.glob("*/seed=*/*/result.json"))
    assert found == sorted(f"{cell}/seed={seed}/env={world}" for cell in ("none_0", "regular_50", "scaffolded_50")
                           for seed in (0, 1) for world in ("default", "tool_frame"))

    assert sensitivity_main(["--random-episodes=50", "--resamples=100", *common]) == 0
    report = (tmp_path / "reports" / "smoke" / "SENSITIVITY.md").read_text()
    table = [line for line in report.splitlines() if line.startswith("| default") or line.startswith("| tool_frame")]
    assert len(table) == 2 and all("2 / 2 / 2" in line for line in table)
    assert "move_frame radial -> tool" in report
    assert (tmp_path / "reports" / "smoke" / "sensitivity" / "sensitivity.png").stat().st_size > 0
    # The hand-written reading survives a rebuild.
    path = tmp_path / "reports" / "smoke" / "SENSITIVITY.md"
    path.write_text(report.replace("(not written yet)", "A person's reading."))
    assert sensitivity_main(["--random-episodes=50", "--resamples=100", *common]) == 0
    assert "A person's reading." in path.read_text()

    # Other learner values: that variant's own report, beside (not over) the study's.
    variant = [*common[:2], "env=default", "seed=0", "algorithm.epsilon=0.2"]
    _run_cli("experiment=sensitivity", "hydra/launcher=basic", *variant)
    assert sensitivity_main(["--random-episodes=50", "--resamples=100", *variant]) == 0
    other = (tmp_path / "reports" / "smoke" / "variants" / "algorithm.epsilon=0.2" / "SENSITIVITY.md").read_text()
    assert "the overrides `algorithm.epsilon=0.2`" in other and "1 / 1 / 1" in other
    assert "A person's reading." in path.read_text() and "overrides" not in path.read_text()

    # The tables' report command skips the study, and named, says where its report comes from.
    from mediated_transfer.reporting.__main__ import main as reporting_main

    with pytest.raises(SystemExit, match="conf/experiment/sensitivity.yaml says how it is reported"):
        reporting_main(["experiment=sensitivity", "scale=smoke", f"paths.root={tmp_path}"])
