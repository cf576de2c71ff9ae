"""Divergence is an outcome: a learner that diverges beyond what rollback absorbs stops its run,
which is recorded as failed (valid JSON, MLflow FAILED with the reason), and tables count it."""

from __future__ import annotations

import json
import math

import pytest

from mediated_transfer.results import RunResult
from mediated_transfer.run import RunSpec, execute_run

from .optional import needs_deep
from .test_sweep import _common, _results, _run_cli, _settings, root, source_cache  # noqa: F401


def strict_json(path):
    def refuse(constant):
        raise ValueError(f"not JSON: {constant}")

    return json.loads(path.read_text(), parse_constant=refuse)


def test_linear_q_with_an_absurd_learning_rate_fails_with_its_reason(tmp_path):
    # Updates move nothing until the first reward; by 10k steps most of them blow up.
    spec = RunSpec(representation="fsr", budget=20_000, eval_points=2, eval_episodes=2,
                   algorithm_params={"alpha0": 1e30})
    result = execute_run(spec)
    assert result.failed and "rolled back" in result.failure and "max_rollback_share" in result.failure
    assert result.steps == [10_000]  # stopped at the first evaluation point that saw it
    assert math.isnan(result.reward_loss) and result.time_to_threshold is None
    result.write(tmp_path)
    stored = strict_json(tmp_path / "result.json")
    assert stored["reward_loss"] is None and stored["failure"] == result.failure
    back = RunResult.read(tmp_path)
    assert back.failed and math.isnan(back.reward_loss)


@needs_deep
def test_the_dqn_with_an_absurd_learning_rate_fails_with_its_reason():
    spec = RunSpec(algorithm="dqn", representation="network", budget=1200, eval_points=3, eval_episodes=2,
                   algorithm_params={"learning_rate": 1e6, "learning_starts": 100, "buffer_size": 1000,
                                     "train_frequency": 1})
    result = execute_run(spec)
    assert result.failed and "diverged by step" in result.failure


def test_a_healthy_run_is_not_failed():
    result = execute_run(RunSpec(representation="fsr", budget=3000, eval_points=3, eval_episodes=2))
    assert not result.failed and result.failure is None and len(result.steps) == 3


@pytest.mark.slow
def test_a_sweep_goes_on_and_its_table_counts_the_failed_runs(root, source_cache, capsys):
    from mediated_transfer.reporting.__main__ import main as reporting_main
    from mediated_transfer.sweep import tracking

    common = ["experiment=table2_rbf", "hydra/launcher=basic", *_common(root, source_cache),
              "scale.budget=20000", "scale.eval_points=2"]
    # Source tasks give rewards at once, so the updates blow up within the first 10k steps.
    _run_cli("-m", "cell=regular_50", "seed=0,1", "algorithm.alpha0=1e30", *common)
    _run_cli("-m", "cell=none_0", "seed=0", *common)
    out = capsys.readouterr().out
    assert out.count("FAILED (diverged by step") == 2
    sweep_dir = root / "multirun" / "table2_rbf" / "smoke"
    failed = [RunResult.read(p.parent) for p in sweep_dir.glob("regular_50/seed=*/*/result.json")]
    assert len(failed) == 2 and all(r.failed for r in failed)
    runs = tracking.find_runs(_settings(root), "table2_rbf", "tags.cell = 'regular_50'")
    assert {r.info.status for r in runs} == {"FAILED"} and all("failure" in r.data.tags for r in runs)
    # Logged once: a rerun finds the failed runs complete (neither recomputed nor re-logged).
    _run_cli("-m", "cell=regular_50", "seed=0,1", "algorithm.alpha0=1e30", *common)
    assert len(tracking.find_runs(_settings(root), "table2_rbf", "tags.cell = 'regular_50'")) == 2
    assert reporting_main(["experiment=table2_rbf", *_common(root, source_cache), "scale.budget=20000",
                           "scale.eval_points=2", "algorithm.alpha0=1e+30"]) == 0  # as Hydra names it
    [table] = (root / "reports" / "smoke" / "variants").rglob("table2_rbf.md")
    row = next(line for line in table.read_text().splitlines() if line.startswith("| regular transfer | 50 "))
    assert "| 0/1 (2 failed) | all failed |" in row
