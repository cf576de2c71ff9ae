"""The plugin examples of docs/extending.md (examples/plugins/, outside src/), end to end at
smoke scale through the command line, as a user runs them: a strategy, a learner and a world
variant, each into a table sweep and its report; and a bad plugin stopped in one line."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PLUGINS = REPO / "examples" / "plugins"
SEARCHPATH = f"hydra.searchpath=[file://{PLUGINS / 'my_plugins' / 'conf'}]"


def _cli(root: Path, *args: str, module: str = "mediated_transfer") -> subprocess.CompletedProcess:
    # Beside the PYTHONPATH the suite runs under (a worktree's src/ before the installed copy).
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(PLUGINS), *filter(None, [os.environ.get("PYTHONPATH")])])}
    return subprocess.run([sys.executable, "-m", module, *args, SEARCHPATH, "tracking=none", "scale=smoke",
                           f"paths.root={root}"], capture_output=True, text=True, env=env, cwd=REPO, timeout=600)


def _sweep_and_report(root: Path, experiment: str, *overrides: str) -> str:
    ran = _cli(root, "-m", f"experiment={experiment}", "hydra/launcher=basic", "seed=0", *overrides)
    assert ran.returncode == 0, ran.stderr[-2000:]
    # The report of the sweep's variant: its overrides beyond the table cell (the folder's name).
    variant = [o for o in overrides if not o.startswith(("cell=", "strategy=", "n_source="))]
    report = _cli(root, f"experiment={experiment}", *variant, module="mediated_transfer.reporting")
    assert report.returncode == 0, report.stderr[-2000:]
    return report.stdout


@pytest.mark.slow
def test_a_users_strategy_runs_in_a_table_sweep_and_gets_its_own_row(tmp_path):
    _sweep_and_report(tmp_path, "table2_rbf", "cell=custom", "strategy=easy_first", "n_source=3")
    result = json.loads((tmp_path / "multirun/table2_rbf/smoke/easy_first_3/seed=0/result.json").read_text())
    assert result["strategy"] == "easy_first" and result["config"]["strategy"]["max_attempts"] == 0
    assert result["code"]["plugins"][0]["target"] == "my_plugins.easy_first.EasyFirst"
    table = (tmp_path / "reports/smoke/table2_rbf.md").read_text()  # the baseline: no variant
    assert "| easy_first | 3 |" in table and "regular transfer" in table


@pytest.mark.slow
def test_a_users_learner_runs_in_a_table_sweep(tmp_path):
    _sweep_and_report(tmp_path, "table3_fsr", "cell=none_0", "algorithm=tabular_q", "representation.distance_bins=5")
    result = json.loads((tmp_path / "multirun/table3_fsr/smoke/none_0/seed=0/algorithm=tabular_q,"
                                    "representation.distance_bins=5/result.json").read_text())
    assert result["algorithm"] == "tabular_q" and result["learner_stats"]["states"] > 1
    assert len(result["mean_reward"]) == 2


@pytest.mark.slow
def test_a_world_variant_with_a_straight_stick_runs_in_a_table_sweep(tmp_path):
    _sweep_and_report(tmp_path, "table2_rbf", "cell=regular_1", "env=straight_stick")
    result = json.loads((tmp_path / "multirun/table2_rbf/smoke/regular_1/seed=0/env=straight_stick/result.json")
                        .read_text())
    assert result["config"]["env"]["tool_hook_angle"] == 180.0


@pytest.mark.parametrize("override,message", [
    ("strategy._target_=my_plugins.easy_firs.EasyFirst", "strategy._target_=my_plugins.easy_firs.EasyFirst: not importable"),
    ("strategy._target_=my_plugins.tabular_q.TabularQ", "TabularQ does not implement the strategy interface: no method 'next_task'"),
    ("+strategy.max_attempt=3", "strategy.max_attempt: not a parameter of my_plugins.easy_first.EasyFirst; allowed: max_attempts"),
    ("strategy.max_attempts=-1", "strategy.max_attempts must be an integer >= 0, got -1"),
])
def test_a_bad_plugin_is_one_line_before_any_work(tmp_path, override, message):
    ran = _cli(tmp_path, "strategy=easy_first", "n_source=3", override)
    assert ran.returncode != 0
    assert message in ran.stderr and "Traceback" not in ran.stderr, ran.stderr[-1500:]
    assert not (tmp_path / "runs").exists()
