"""The pre-registered DQN failure ablation's decision rule (conf/experiment/dqn_failure_ablation.yaml)
on known counts, and its report from a tree of runs."""

from __future__ import annotations

import numpy as np
import pytest

from mediated_transfer.reporting.ablation import (EXPERIMENT, decidable, decide, fewer_failures_p, main,
                                                  seed_clustering_p, table_i_values)
from mediated_transfer.results import RunResult

from .optional import needs_deep

STEPS = [100, 200, 300, 400]
LEARNS, NEVER = [0.0, 9.0, 9.5, 9.8], [0.0, 0.2, 0.0, 0.1]


def test_fisher_p_values_are_the_ones_the_registration_quotes():
    # conf/experiment/dqn_failure_ablation.yaml: 0 of 20 against 5 of 20 gives p = 0.024,
    # 0 of 20 against 4 of 20 gives p = 0.053.
    assert fewer_failures_p(0, 20, 5, 20) == pytest.approx(0.024, abs=5e-4)
    assert fewer_failures_p(0, 20, 4, 20) == pytest.approx(0.053, abs=5e-4)
    assert fewer_failures_p(5, 20, 0, 20) == pytest.approx(1.0)  # more failures: no evidence of fewer


def test_the_study_decides_only_from_five_table_i_failures_at_twenty_runs_an_arm():
    # The registration: with fewer than 5 failures in the Table I arm the study cannot decide.
    assert [decidable(k, 20, 20) for k in range(3, 7)] == [False, False, True, True]


@pytest.mark.parametrize("buffer_arm,epsilon_arm,verdict", [
    ((0, 20), (5, 20), "H1 supported"),
    ((6, 20), (0, 20), "H2 supported"),
    ((0, 20), (1, 20), "both single-factor arms"),
    ((3, 20), (4, 20), "neither supported"),
])
def test_a_hypothesis_is_supported_when_its_arm_removes_the_failure_and_the_other_does_not(
        buffer_arm, epsilon_arm, verdict):
    assert decide(buffer_arm, epsilon_arm, (6, 20)).startswith(verdict)


def test_too_few_table_i_failures_cannot_decide_whatever_the_arms_show():
    assert decide((0, 20), (4, 20), (4, 20)).startswith("cannot decide")


def _write(root, buffer_size, epsilon_decay, seed, curve):
    overrides = [f"algorithm.{key}={value}" for key, value in
                 zip(("buffer_size", "epsilon_decay_steps"), (buffer_size, epsilon_decay))]
    folder = root / "multirun" / EXPERIMENT / "paper" / "none_0" / f"seed={seed}" / ",".join(overrides)
    result = RunResult("dqn", "network", "none", 0, seed, 400, STEPS, list(curve), [r / 10 for r in curve],
                       sum(10 - r for r in curve), None, None, 0, 1.0, 1.0,
                       learner_stats={"episodes": 5000.0, "last_loss": 1e-6}, first_target_reward_step=150,
                       config={"algorithm": {"buffer_size": buffer_size, "epsilon_decay_steps": epsilon_decay}})
    result.write(folder)


def test_the_report_names_each_arm_and_applies_the_rule(tmp_path):
    big_buffer, long_decay = 100_000, 50_000
    buffer, decay = table_i_values()
    for seed in range(2000, 2010):
        _write(tmp_path, buffer, decay, seed, NEVER if seed < 2006 else LEARNS)       # 6 of 10 fail
        _write(tmp_path, big_buffer, decay, seed, LEARNS)                              # 0 of 10
        _write(tmp_path, buffer, long_decay, seed, NEVER if seed < 2005 else LEARNS)   # 5 of 10
    out = tmp_path / "ablation.md"
    assert main(["--root", str(tmp_path), "--out", str(out)]) == 0
    text = out.read_text()
    assert "**Incomplete:** 30 of 80 runs" in text
    assert "| Table I | 21,255 | 10,929 | 10 | 6 |" in text
    assert "| buffer 100,000 | 100,000 | 10,929 | 10 | 0 |" in text
    assert "| ε decay 50,000 | 21,255 | 50,000 | 10 | 5 |" in text
    assert "**Decision:** H1 supported" in text
    assert text.count("| Table I | 200") == 6  # each run that never learns, with its seed
    # By seed: L_R per arm (Table I, buffer, epsilon), the runs that never learn in bold.
    assert "| 2000 | **39.7** | 11.7 | **39.7** | 2 of 3 |" in text
    assert "| 2005 | **39.7** | 11.7 | 11.7 | 1 of 3 |" in text
    assert "| 2009 | 11.7 | 11.7 | 11.7 | 0 of 3 |" in text
    assert "Over the 10 seeds that every arm has run" in text
    # Every run's curve, a panel per arm, beside the report and linked from it.
    assert "![Every run's curve, a panel per arm](ablation.png)" in text
    assert (tmp_path / "ablation.png").stat().st_size > 0


def test_failures_on_the_same_seeds_are_unlikely_by_chance_and_spread_ones_are_not():
    same = np.zeros((4, 10), dtype=bool)
    same[:, :2] = True                        # every arm fails on seeds 0 and 1
    spread = np.eye(4, 10, dtype=bool)        # each arm fails on a seed of its own
    assert seed_clustering_p(same) < 0.01
    assert seed_clustering_p(spread) == 1.0   # no shuffle spreads them more evenly
    assert seed_clustering_p(same) == seed_clustering_p(same)  # seeded
    mixed = same.copy()
    mixed[0] = np.roll(mixed[0], 5)           # one arm's failures elsewhere: weaker evidence
    assert seed_clustering_p(same) < seed_clustering_p(mixed) < 1.0


def test_without_table_i_runs_the_report_says_how_to_start_and_draws_nothing(tmp_path):
    out = tmp_path / "ablation.md"
    assert main(["--root", str(tmp_path), "--out", str(out)]) == 0
    assert "No runs of the Table I arm yet" in out.read_text()
    assert not (tmp_path / "ablation.png").exists()


@pytest.mark.slow
@needs_deep
def test_the_registered_sweep_runs_every_arm_in_its_own_folder_and_reports_it(tmp_path):
    """The experiment as registered, at smoke scale on one seed: four arms, each in its own folder,
    and a report with a row per arm."""
    from .test_sweep import _run_cli
    from .test_tracking import fresh_store

    fresh_store(tmp_path)
    _run_cli(f"experiment={EXPERIMENT}", "hydra/launcher=basic", "scale=smoke", "seed=2000",
             f"paths.root={tmp_path}")
    sweep = tmp_path / "multirun" / EXPERIMENT / "smoke" / "none_0" / "seed=2000"
    assert sorted(p.parent.name for p in sweep.glob("*/result.json")) == sorted(
        f"algorithm.buffer_size={b},algorithm.epsilon_decay_steps={e}" for b in (21255, 100000) for e in (10929, 50000))
    out = tmp_path / "ablation.md"
    assert main(["--root", str(tmp_path), "--scale", "smoke", "--out", str(out)]) == 0
    text = out.read_text()
    for arm in ("| Table I |", "| buffer 100,000 |", "| ε decay 50,000 |", "| buffer 100,000 + ε decay 50,000 |"):
        assert arm in text
