"""The world door (env/door.py): the paper's world is an ``env`` option with a ``_target_``, and
the example worlds of docs/extending.md (examples/worlds/, outside src/) run end to end at
smoke scale through the command line, as a user runs them: a table sweep and its report, and
an animation; a bad key of a world is one line before any work."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mediated_transfer.config.compose import ConfigError, compose_config
from mediated_transfer.config.spec import comparable, run_spec, spec_from_dict

from .optional import needs_deep
from .two_tool_world import TwoToolTask, TwoToolWorld

REPO = Path(__file__).resolve().parents[1]
WORLDS = REPO / "examples" / "worlds"
SEARCHPATH = "hydra.searchpath=[pkg://my_worlds.conf]"


def _cli(root: Path, *args: str, module: str = "mediated_transfer", smoke: bool = True) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(WORLDS), os.environ.get("PYTHONPATH", "")])}
    extra = ["tracking=none", "scale=smoke", f"paths.root={root}"] if smoke else []
    return subprocess.run([sys.executable, "-m", module, *args, SEARCHPATH, *extra],
                          capture_output=True, text=True, env=env, cwd=REPO, timeout=600)


def _sweep_and_report(root: Path, experiment: str, cell: str, world: str) -> dict:
    ran = _cli(root, "-m", f"experiment={experiment}", "hydra/launcher=basic", "seed=0", f"cell={cell}", f"env={world}")
    assert ran.returncode == 0, ran.stderr[-2000:]
    report = _cli(root, f"experiment={experiment}", f"env={world}", module="mediated_transfer.reporting")
    assert report.returncode == 0, report.stderr[-2000:]
    return json.loads((root / f"multirun/{experiment}/smoke/{cell}/seed=0/env={world}/result.json").read_text())


def test_the_paper_world_comes_through_the_door_with_its_target():
    spec = run_spec(compose_config(["scale=smoke"]))
    assert spec.world_target == "mediated_transfer.env.paper.PaperWorld"
    assert type(spec.make_world()).__name__ == "PaperWorld"
    # A result recorded before worlds had a _target_ is the same run (the paper's world).
    values = comparable(spec)
    recorded = spec_from_dict({**{k: v for k, v in values.items()}, "world_target": None})
    assert comparable(recorded) == values and recorded.make_world().config == spec.world


@pytest.mark.parametrize("override,message", [
    ("env._target_=nowhere.World", "env._target_=nowhere.World: not importable"),
    ("env._target_=mediated_transfer.env.config.WorldConfig",
     "env._target_=mediated_transfer.env.config.WorldConfig: WorldConfig does not implement the world interface: no method 'make_env'"),
    ("env.goal_radiu=1", "unknown key 'env.goal_radiu'; did you mean 'env.goal_radius'?"),
])
def test_a_bad_world_is_one_line(override, message):
    with pytest.raises(ConfigError, match="^" + message.replace("(", r"\(").replace(".", r"\.").replace("?", r"\?")):
        run_spec(compose_config(["scale=smoke", override]))


@pytest.mark.slow
def test_a_rake_runs_in_a_table_sweep_and_its_report(tmp_path):
    result = _sweep_and_report(tmp_path, "table2_rbf", "regular_1", "rake")
    assert result["config"]["env"]["_target_"] == "my_worlds.rake.RakeWorld"
    assert result["config"]["env"]["rake_head_length"] == 6.0
    reports = [p for p in tmp_path.glob("reports/**/*.md") if "rake" in str(p)]
    assert reports and "regular transfer" in reports[0].read_text(), sorted(tmp_path.glob("reports/**/*"))


@pytest.mark.slow
def test_a_world_with_an_extra_sensor_runs_in_a_table_sweep_and_its_report(tmp_path):
    result = _sweep_and_report(tmp_path, "table3_fsr", "none_0", "target_distance")
    assert result["config"]["env"]["_target_"] == "my_worlds.sensor.TargetDistanceWorld"
    assert len(result["mean_reward"]) == 2


@pytest.mark.slow
@pytest.mark.parametrize("world,policy", [("rake", "random"), ("target_distance", "scripted")])
def test_animate_shows_a_plugin_world(tmp_path, world, policy):
    out = tmp_path / f"{world}.gif"
    ran = _cli(tmp_path, "--env", world, "--out", str(out), "--seed", "1", module="mediated_transfer.env.animate",
               smoke=False)
    assert ran.returncode == 0, ran.stderr[-2000:]
    assert out.stat().st_size > 0 and f"{policy} policy on a target task" in ran.stdout


def test_a_bad_key_of_a_plugin_world_is_one_line_before_any_work(tmp_path):
    ran = _cli(tmp_path, "env=rake", "env.rake_head_lengt=3")
    assert ran.returncode != 0 and "Traceback" not in ran.stderr, ran.stderr[-1500:]
    assert "unknown key 'env.rake_head_lengt'; did you mean 'env.rake_head_length'?" in ran.stderr
    ran = _cli(tmp_path, "env=rake", "env.rake_head_length=-1")
    assert "env.rake_head_length must be > 0, got -1" in ran.stderr, ran.stderr[-1500:]
    assert not (tmp_path / "runs").exists()


@needs_deep
def test_the_dqn_and_its_stacked_form_take_the_extra_sensor_world_s_layout(monkeypatch):
    """The deep Q-network reads the world's sensors (7 distances, then the 5-dim one-hot), in a
    single run, and stacked in a lockstep group; the memory estimate counts its replay rows."""
    from mediated_transfer.learners.dqn import DQNConfig
    from mediated_transfer.learners.factory import make_learner, memory_bytes, validate_learner_choice
    from mediated_transfer.lockstep.run import execute_lockstep
    from mediated_transfer.lockstep.stacked import StackedDQN
    from mediated_transfer.run import RunSpec, RunStreams, execute_run

    monkeypatch.syspath_prepend(str(WORLDS))
    params = {"hidden_size": 16, "num_hidden_layers": 2, "learning_starts": 64, "buffer_size": 300,
              "target_update_interval": 50, "epsilon_decay_steps": 200}
    specs = [RunSpec(algorithm="dqn", representation="network", strategy="regular", n_source=1, seed=seed,
                     budget=600, eval_points=3, eval_episodes=2, source_pool_size=50, algorithm_params=params,
                     world_target="my_worlds.sensor.TargetDistanceWorld").validate() for seed in (0, 1)]
    world = specs[0].make_world()
    assert world.sensors.num_distances == 7 and world.sensors.size == 12
    learner = make_learner("dqn", "network", params, world=world)
    assert learner.network.shapes[0] == (16, 7) and learner.network.shapes[-1] == (11, 16 + 5)
    assert learner.buffer.WIDTH == 2 * 12 + 3
    config, _ = validate_learner_choice("dqn", "network", params, {})
    assert memory_bytes("dqn", config, None, world) > memory_bytes("dqn", config, None)  # wider rows
    result = execute_run(specs[0])
    assert result.failure is None and len(result.mean_reward) == 3 and result.learner_stats["updates"] > 0
    group = StackedDQN(DQNConfig(**params), [RunStreams.of(s).learner_seed for s in specs],
                       num_actions=world.num_actions, sensors=world.sensors)
    for lock in execute_lockstep(specs, group=group):
        assert lock.failure is None and len(lock.mean_reward) == 3 and lock.learner_stats["updates"] > 0


def test_source_tasks_are_clustered_on_the_world_s_own_sensors(monkeypatch, tmp_path):
    """The extra-sensor world's C is clustered, and eq. (3) compares, on the vectors its agent
    observes (7 distances); its cached sets are its own, not the paper's world's."""
    from mediated_transfer.env.paper import PaperWorld
    from mediated_transfer.transfer.source_tasks import source_task_set
    from mediated_transfer.transfer.strategy import StrategyContext

    monkeypatch.syspath_prepend(str(WORLDS))
    from my_worlds.sensor import TargetDistanceWorld

    world, paper = TargetDistanceWorld(PaperWorld().config), PaperWorld()
    tasks = source_task_set(5, world, pool_size=200, seed=3, cache_dir=tmp_path)
    assert len(list(tmp_path.iterdir())) == 1
    assert source_task_set(5, world, pool_size=200, seed=3, cache_dir=tmp_path) == tasks  # read back
    source_task_set(5, paper, pool_size=200, seed=3, cache_dir=tmp_path)
    assert len(list(tmp_path.iterdir())) == 2  # the paper's world's set is another file
    context = StrategyContext.of_tasks(tasks, np.random.default_rng(0), world=world)
    assert context.sensors.shape == (5, 12)
    assert context.sensors[:, 6].tolist() == pytest.approx([t.target_distance for t in tasks])


def test_a_world_whose_tasks_hold_two_tools_gets_its_source_tasks_and_scaffolding(tmp_path):
    """Nothing in the source task set or the strategies assumes the paper's task: a world whose
    tasks hold two tools is clustered on its own sensors, cached and read back as its own tasks,
    and Algorithm 2 orders them by eq. (3) on those sensors."""
    from mediated_transfer.transfer.source_tasks import source_task_set
    from mediated_transfer.transfer.strategy import EpisodeOutcome, StrategyContext, make_strategy

    world = TwoToolWorld()
    tasks = source_task_set(4, world, pool_size=100, seed=0, cache_dir=tmp_path)
    assert all(isinstance(t, TwoToolTask) and len(t.tools) == 2 for t in tasks)
    assert source_task_set(4, world, pool_size=100, seed=0, cache_dir=tmp_path) == tasks  # from the file
    context = StrategyContext.of_tasks(tasks, np.random.default_rng(0), world=world)
    assert context.sensors.shape == (4, 8)
    strategy = make_strategy("scaffolded", tasks, rng=np.random.default_rng(0), world=world)
    seen = []
    for step in range(40):
        task = strategy.next_task()
        if task is None:
            break
        seen.append(task)
        strategy.report(EpisodeOutcome(task=task, solved=True, episode_return=10.0, length=5, step=step * 5))
    assert set(seen) == set(tasks)  # each source task of the world, until C is solved


def test_the_run_loop_learns_on_a_world_whose_tasks_hold_two_tools(tmp_path):
    """The one run loop, end to end, on a world that is not the paper's (tests/two_tool_world.py):
    C clustered on its sensors and cached as its tasks, scaffolded source episodes, evaluation on
    its target tasks, the exposure counted from its tasks' target distance."""
    from mediated_transfer.run import RunSpec, execute_run

    spec = RunSpec(algorithm="linear_q", representation="fsr", strategy="scaffolded", n_source=3, seed=0,
                   budget=3000, eval_points=3, eval_episodes=5, source_pool_size=60, cache_dir=str(tmp_path),
                   world_target="tests.two_tool_world.TwoToolWorld").validate()
    assert isinstance(spec.make_world(), TwoToolWorld)
    result = execute_run(spec)
    assert result.failure is None and len(result.mean_reward) == 3
    assert result.source_tasks_solved == 3 and result.source_phase_end is not None  # the pulls are easy
    assert result.choices is not None and any(share > 0 for share in result.choices["target_share"])
    assert execute_run(spec).mean_reward == result.mean_reward  # same seed, same curve
