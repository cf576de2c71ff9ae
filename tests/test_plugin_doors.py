"""A plugin goes everywhere a built-in goes (issue 44): a user's package outside src/ with a
SARSA(lambda) learner that subclasses the linear Q learner, as a new user writes it.

``--help`` lists its options; it gets the linear learner's Table I values (its own keys win) and
the run says which tuned file applied; its result.json records it as a plugin; ``evaluate --run``
loads its run; a bad key of its YAML and an unreadable ``pkg://`` path are one line before any
folder exists."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from omegaconf import OmegaConf

from mediated_transfer.config.compose import CONF_DIR, ConfigError, compose_config, prepare_overrides
from mediated_transfer.config.tuned import tuned_line

REPO = Path(__file__).resolve().parents[1]
SEARCHPATH = "hydra.searchpath=[pkg://sarsa_plugins.conf]"
TUNED_RBF = OmegaConf.load(CONF_DIR / "tuned" / "linear_q_rbf.yaml")


@pytest.fixture
def package(tmp_path: Path) -> Path:
    """sarsa_plugins/: a learner extending the linear Q learner, two YAMLs, one with a bad key."""
    root = tmp_path / "user"
    pkg = root / "sarsa_plugins"
    (pkg / "conf" / "algorithm").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "conf" / "__init__.py").write_text("")
    (pkg / "sarsa.py").write_text(
        "from mediated_transfer.learners.linear_q import LinearQLearner\n\n\n"
        "class Sarsa(LinearQLearner):\n    \"\"\"The subclass is what matters here.\"\"\"\n")
    (pkg / "conf" / "algorithm" / "sarsa.yaml").write_text(
        "defaults:\n  - linear_q\n  - _self_\n_target_: sarsa_plugins.sarsa.Sarsa.from_params\nname: sarsa\ngamma: 0.9\n")
    # No defaults: the learner's keys are the plugin's alone; `lambda` is not one of them.
    (pkg / "conf" / "algorithm" / "bare.yaml").write_text(
        "_target_: sarsa_plugins.sarsa.Sarsa.from_params\nname: bare\nlambda: 0.5\n")
    return root


def _cli(package: Path, *args: str, module: str = "mediated_transfer") -> subprocess.CompletedProcess:
    paths = [str(package), *filter(None, [os.environ.get("PYTHONPATH")])]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(paths)}
    return subprocess.run([sys.executable, "-m", module, *args], capture_output=True, text=True, env=env,
                          cwd=package.parent, timeout=300)


def test_help_lists_the_options_of_the_search_path(package):
    shown = _cli(package, "--help", SEARCHPATH)
    assert shown.returncode == 0, shown.stderr
    groups = dict(line.split(": ", 1) for line in shown.stdout.splitlines() if line.startswith(("algorithm: ", "tuned: ")))
    assert groups["algorithm"].split(", ") == ["bare", "dqn", "linear_q", "sarsa", "sb3_dqn", "sb3_ppo"]
    assert "sarsa_rbf" in groups["tuned"].split(", ")


def test_a_learner_extending_a_builtin_gets_its_table_i_values_less_its_own_keys(package, monkeypatch):
    monkeypatch.syspath_prepend(str(package))
    cfg = compose_config(["algorithm=sarsa", f"hydra.searchpath=[file://{package}/sarsa_plugins/conf]"])
    assert cfg.algorithm.epsilon == TUNED_RBF.algorithm.epsilon and cfg.algorithm.lambda_ == TUNED_RBF.algorithm.lambda_
    assert cfg.algorithm.gamma == 0.9  # its YAML's own value, not Table I's 0.98
    assert cfg.representation.tool_target_high == TUNED_RBF.representation.tool_target_high
    # The plugin says otherwise: ~tuned runs the provisional defaults, as for a built-in.
    plain = compose_config(["algorithm=sarsa", "~tuned", f"hydra.searchpath=[file://{package}/sarsa_plugins/conf]"])
    assert plain.algorithm.epsilon != TUNED_RBF.algorithm.epsilon


def test_the_tuned_line_names_the_file_or_none():
    line = tuned_line({"tuned": "linear_q_fsr", "algorithm": "linear_q", "representation": "fsr"}, [])
    assert line == "tuned: conf/tuned/linear_q_fsr.yaml applied to algorithm=linear_q representation=fsr"
    assert tuned_line({"tuned": "sb3_ppo_rbf", "algorithm": "sb3_ppo", "representation": "rbf"}, []).startswith(
        "tuned: none (no tuned file sb3_ppo_rbf.yaml)")
    assert tuned_line({"tuned": None, "algorithm": "dqn", "representation": "network"}, []).startswith("tuned: none (~tuned)")


@pytest.mark.slow
def test_a_plugin_learners_run_records_it_says_its_tuned_file_and_evaluates(package, tmp_path):
    ran = _cli(package, "algorithm=sarsa", SEARCHPATH, "scale=smoke", "tracking=none", f"paths.root={tmp_path}")
    assert ran.returncode == 0, ran.stderr[-2000:]
    assert ("tuned: conf/tuned/linear_q_rbf.yaml (Table I of the built-in learner that algorithm=sarsa extends)"
            in ran.stderr + ran.stdout)
    [result_file] = (tmp_path / "runs").rglob("result.json")
    result = json.loads(result_file.read_text())
    assert result["code"]["plugins"] == [{"target": "sarsa_plugins.sarsa.Sarsa.from_params",
                                          "distribution": None, "version": None}]
    assert result["config"]["algorithm"]["epsilon"] == TUNED_RBF.algorithm.epsilon
    evaluated = _cli(package, "--run", str(result_file.parent), module="mediated_transfer.evaluate")
    assert evaluated.returncode == 0, evaluated.stderr
    assert "sarsa/rbf none N_source=0 seed=0, greedy on 2 target tasks" in evaluated.stdout
    # Without the plugin's package the run cannot be loaded: one line, naming PYTHONPATH.
    alone = subprocess.run([sys.executable, "-m", "mediated_transfer.evaluate", "--run", str(result_file.parent)],
                           capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert alone.returncode != 0 and len(alone.stderr.strip().splitlines()) == 1
    assert "not importable" in alone.stderr and "PYTHONPATH" in alone.stderr


def test_a_bad_key_of_a_plugin_learner_is_one_line_before_any_folder(package, tmp_path):
    ran = _cli(package, "algorithm=bare", SEARCHPATH, "scale=smoke", "tracking=none", f"paths.root={tmp_path}")
    assert ran.returncode != 0
    assert ran.stderr.strip() == ("Invalid configuration: algorithm: unknown key(s) lambda (did you mean "
                                  "'algorithm.lambda_' for lambda?); allowed: epsilon, "
                                  "lambda_, gamma, alpha0, boyan_n0, alpha_decay, trace_cutoff, max_rollback_share")
    assert not (tmp_path / "runs").exists()


def test_an_unreadable_pkg_path_names_pythonpath_or_the_missing_init(package, monkeypatch):
    for name in [m for m in sys.modules if m.split(".")[0] == "sarsa_plugins"]:  # imported by another test
        monkeypatch.delitem(sys.modules, name)
    with pytest.raises(ConfigError, match=r"^hydra.searchpath: pkg://sarsa_plugins.conf: sarsa_plugins.conf cannot "
                                          r"be imported .*; put the folder that holds sarsa_plugins/ on PYTHONPATH"):
        prepare_overrides([SEARCHPATH])
    monkeypatch.syspath_prepend(str(package))
    (package / "sarsa_plugins" / "conf" / "__init__.py").unlink()
    with pytest.raises(ConfigError, match=r"sarsa_plugins/conf has no __init__.py; .*add an empty one$"):
        prepare_overrides([SEARCHPATH])
    with pytest.raises(ConfigError, match=r"^hydra.searchpath: file://nowhere: no such folder"):
        prepare_overrides(["hydra.searchpath=[file://nowhere]"])
