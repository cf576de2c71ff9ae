"""Start-up: what a linear run imports. torch costs about a second to import, and only the deep
learners use it, so the entry point, composing and checking a config, and a linear run's loop
must not import it (learners/dqn_config.py holds what they need of the DQN)."""

from __future__ import annotations

import subprocess
import sys


def _imports_after(code: str) -> set[str]:
    probe = code + "\nimport sys\nprint(' '.join(sorted(m.split('.')[0] for m in sys.modules)))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True)
    return set(out.stdout.split())


def test_a_linear_run_imports_no_torch():
    loaded = _imports_after(
        "from mediated_transfer.app import main\n"
        "from mediated_transfer.config.compose import compose_config\n"
        "from mediated_transfer.config.spec import run_spec\n"
        "from mediated_transfer.run import execute_run\n"
        "spec = run_spec(compose_config(['scale=smoke', 'scale.budget=100', 'scale.eval_points=1',"
        " 'scale.eval_episodes=1']))\n"
        "assert execute_run(spec).steps == [100]")
    assert "mediated_transfer" in loaded and "torch" not in loaded and "stable_baselines3" not in loaded


def test_composing_a_dqn_config_imports_no_torch():
    # Checking it may (its memory estimate reads the replay buffer's layout): it asks for torch.
    loaded = _imports_after(
        "from mediated_transfer.config.compose import compose_config\n"
        "compose_config(['algorithm=dqn', 'representation=network', 'scale=smoke'])")
    assert "torch" not in loaded
