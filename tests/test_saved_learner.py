"""A run saves its trained learner (plain arrays / tensors, read without unpickling); it reloads
to the same greedy actions; the evaluate and GIF commands run on a smoke run's folder."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mediated_transfer import evaluate as evaluate_cli
from mediated_transfer.env import MediatedInteractionEnv, animate
from mediated_transfer.provenance.judge import stale
from mediated_transfer.results import RunResult
from mediated_transfer.run import RunSpec, execute_run
from mediated_transfer.stored import codec
from mediated_transfer.saved_learner import (DQN_FILE, LINEAR_FILE, SavedLearnerError, load_learner,
                                             save_learner)

from .optional import needs_deep
from .test_run import TINY
from .test_sweep import _run_cli

LINEAR = ("linear_q", "rbf", {})
DQN = ("dqn", "network", {"learning_starts": 100, "buffer_size": 1000})
LEARNERS = [LINEAR, DQN]  # DQN skips without the deep extra (conftest.py)


def _observations(n: int = 300) -> list[np.ndarray]:
    """Observations met in target-task episodes of a random policy."""
    env, rng = MediatedInteractionEnv("target"), np.random.default_rng(0)
    observations = [env.reset(seed=0)[0]]
    while len(observations) < n:
        obs, _, terminated, truncated, _ = env.step(int(rng.integers(env.action_space.n)))
        observations.append(env.reset()[0] if terminated or truncated else obs)
    return observations


@pytest.mark.parametrize("algorithm, representation, params", LEARNERS)
def test_a_saved_learner_reloads_to_the_same_greedy_actions(tmp_path, algorithm, representation, params):
    # Source tasks (target within reach) are rewarded early: the weights are not all zero.
    spec = RunSpec(algorithm=algorithm, representation=representation, strategy="regular",
                   n_source=3, seed=2, cache_dir=str(tmp_path / "cache"), algorithm_params=params,
                   **{**TINY, "budget": 1500})
    trained = {}

    def finish(learner):
        trained["learner"] = learner
        trained["path"] = save_learner(learner, spec, tmp_path / "run")

    execute_run(spec, on_finish=finish)
    learner, back = load_learner(tmp_path / "run")
    assert back == spec
    assert trained["path"].name == (DQN_FILE if algorithm == "dqn" else LINEAR_FILE)
    observations = _observations()
    actions = [trained["learner"].act(obs, explore=False) for obs in observations]
    assert [learner.act(obs, explore=False) for obs in observations] == actions
    assert len(set(actions)) > 1  # a learner that has learned something
    if algorithm == "dqn":
        import torch

        assert torch.equal(learner.network.flat, trained["learner"].network.flat)
    else:
        assert np.array_equal(learner.theta, trained["learner"].theta)


@needs_deep
def test_the_files_are_plain_arrays_and_tensors_read_without_unpickling(tmp_path):
    import torch

    for algorithm, representation, params in LEARNERS:
        spec = RunSpec(algorithm=algorithm, representation=representation, algorithm_params=params,
                       **{**TINY, "budget": 300, "eval_points": 1})
        execute_run(spec, on_finish=lambda learner: save_learner(learner, spec, tmp_path / algorithm))
    with np.load(tmp_path / "linear_q" / LINEAR_FILE, allow_pickle=False) as data:
        assert all(data[key].dtype != object for key in data.files)
        assert json.loads(str(data["meta"]))["spec"]["representation"] == "rbf"
    state = torch.load(tmp_path / "dqn" / DQN_FILE, weights_only=True)
    # The replay buffer is not kept: the network is what acts.
    assert state["buffer_size"] == 0 and state["buffer_transitions"].shape[0] == 0


@needs_deep
def test_the_format_follows_the_learner_s_state_not_its_algorithm_s_name(tmp_path):
    """A plugin learner that extends the DQN (another algorithm name) is saved as the DQN is:
    tensors in learner.pt, without its replay buffer; SB3's nested policy tensors too."""
    import torch

    from mediated_transfer.learners.factory import make_learner
    from mediated_transfer.saved_learner import holds_tensors

    spec = RunSpec(algorithm="dqn", representation="network", algorithm_params=DQN[2], **TINY)
    learner = make_learner("dqn", "network", DQN[2], seed=0)
    plugin = type("MyDQN", (type(learner),), {})  # a subclass, as a plugin would write it
    learner.__class__ = plugin
    path = save_learner(learner, spec.__class__(**{**spec.__dict__, "algorithm": "my_dqn"}), tmp_path)
    assert path.name == DQN_FILE and torch.load(path, weights_only=True)["buffer_size"] == 0
    assert holds_tensors({"policy": {"w": torch.zeros(2)}, "num_timesteps": 3})
    assert not holds_tensors({"weights": np.zeros(3), "steps": 4})


def test_a_file_that_would_need_unpickling_is_refused(tmp_path):
    folder = tmp_path / "run"
    folder.mkdir()
    np.savez(folder / LINEAR_FILE, meta=np.array([{"format": 1}], dtype=object))
    with pytest.raises(SavedLearnerError, match="cannot be loaded.*allow_pickle"):
        load_learner(folder)


@pytest.fixture(scope="module")
def source_cache(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("source_task_cache")


def _smoke_run(root: Path, cache: Path, *overrides: str) -> Path:
    _run_cli("scale=smoke", f"paths.root={root}", f"paths.cache_dir={cache}", "tracking=none", *overrides)
    [result] = root.glob("runs/**/result.json")
    return result.parent


@pytest.mark.slow
@pytest.mark.parametrize("algorithm, representation", [("linear_q", "fsr"), ("dqn", "network")])
def test_evaluate_and_animate_run_on_a_smoke_runs_folder(tmp_path, source_cache, capsys,
                                                         algorithm, representation):
    folder = _smoke_run(tmp_path, source_cache, f"algorithm={algorithm}",
                        f"representation={representation}")
    run = RunResult.read(folder)
    # By default the run's own evaluation tasks and noise: its last evaluation point again.
    result = evaluate_cli.main(["--run", str(folder)])
    assert (result.mean_reward, result.success_rate) == (run.mean_reward[-1], run.success_rate[-1])
    assert result.episodes == 2  # smoke scale's eval_episodes
    result = evaluate_cli.main(["--run", str(folder), "--episodes", "3", "--seed", "5"])
    assert result.episodes == 3 and 0.0 <= result.success_rate <= 1.0
    out = capsys.readouterr().out
    assert "<R> = " in out and "success rate" in out and "last evaluation point" in out

    gif = tmp_path / "trained.gif"
    summary = animate.main(["--run", str(folder), "--seed", "3", "--out", str(gif)])
    with Image.open(gif) as image:
        assert image.n_frames == summary["steps"] + 1
    assert f"trained ({algorithm}/{representation}" in capsys.readouterr().out


@pytest.mark.slow
def test_save_learner_false_saves_none_and_the_commands_say_so_in_one_line(tmp_path, source_cache):
    folder = _smoke_run(tmp_path, source_cache, "save_learner=false")
    assert not list(folder.glob("learner.*"))
    for command in (evaluate_cli.main, animate.main):
        with pytest.raises(SystemExit) as exit_info:
            command(["--run", str(folder), "--out", str(tmp_path / "x.gif")] if command is animate.main
                    else ["--run", str(folder)])
        message = str(exit_info.value.code)
        assert "holds no saved learner" in message and "\n" not in message


@pytest.mark.slow
def test_a_recomputed_run_does_not_keep_the_learner_of_the_run_before(tmp_path, source_cache):
    folder = _smoke_run(tmp_path, source_cache)
    assert (folder / LINEAR_FILE).is_file()
    stored = json.loads((folder / "result.json").read_text())
    stored["code"] = {"commit": "0" * 40, "dirty": False, "digest": "0" * 16}  # as if older code wrote it
    stored["checksum"] = codec.checksum(stored)  # sealed as the committed runs are
    (folder / "result.json").write_text(json.dumps(stored))
    _smoke_run(tmp_path, source_cache, "rerun_stale=true", "save_learner=false")
    assert stale(RunResult.read(folder)) is None and not (folder / LINEAR_FILE).exists()


def test_saved_learners_stay_out_of_git():
    repo = Path(__file__).resolve().parents[1]
    if not (repo / ".git").exists():
        pytest.skip("not a git checkout")
    paths = ["multirun/table2_rbf/paper/none_0/seed=0/learner.npz",
             "multirun/table4_dnn/paper/none_0/seed=0/learner.pt", "runs/x/smoke/none_0/seed=0/learner.npz"]
    ignored = subprocess.run(["git", "check-ignore", *paths], cwd=repo, capture_output=True, text=True)
    assert ignored.stdout.split() == paths
