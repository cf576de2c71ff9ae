"""Lockstep: K runs of one cell stepped together in one process (lockstep/). Per seed, the CPU
group computes its single run bit for bit; the stacked networks (the GPU path, run here on the
CPU) follow the reference update within float32 tolerance; a diverged run fails alone; the
launchers group a cell's unfinished seeds; results record the lockstep code."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from .optional import importorskip

torch = importorskip("torch")

from mediated_transfer.learners.dqn import DQNConfig, DQNLearner
from mediated_transfer.lockstep.group import PerSeedLearners
from mediated_transfer.lockstep.run import RunHooks, check_group, execute_lockstep, make_group
from mediated_transfer.lockstep.stacked import StackedDQN
from mediated_transfer.provenance.judge import stale
from mediated_transfer.run import RunSpec, RunStreams, execute_run

# A small network and an early start, so that updates, target copies and the epsilon decay all
# happen within a few hundred steps.
DQN_PARAMS = {"hidden_size": 32, "learning_starts": 64, "buffer_size": 300, "target_update_interval": 50,
              "epsilon_decay_steps": 200, "train_frequency": 1}


def dqn_spec(seed: int = 0, **changes) -> RunSpec:
    values = dict(algorithm="dqn", representation="network", strategy="regular", n_source=1, seed=seed,
                  budget=600, eval_points=3, eval_episodes=4, source_pool_size=50,
                  algorithm_params=DQN_PARAMS)
    values.update(changes)
    return RunSpec(**values)


def outcome(result) -> tuple:
    """Everything a run's result says about what it learned."""
    return (result.steps, result.mean_reward, result.success_rate, result.reward_loss,
            result.time_to_threshold, result.source_phase_end, result.first_target_reward_step,
            result.source_tasks_solved, result.learner_stats, result.failure)


def final_weights(spec: RunSpec, runner) -> tuple:
    saved = {}
    result = runner(lambda learner: saved.update(learner.state_dict()))
    return result, saved


@pytest.mark.parametrize("strategy,n_source", [("none", 0), ("regular", 1), ("scaffolded", 2)])
def test_each_run_of_a_cpu_group_is_its_single_run_bit_for_bit(strategy, n_source):
    specs = [dqn_spec(seed, strategy=strategy, n_source=n_source) for seed in (0, 1, 2)]
    singles, single_states = [], []
    for spec in specs:
        state = {}
        singles.append(execute_run(spec, on_finish=lambda learner, s=state: s.update(learner.state_dict())))
        single_states.append(state)
    states = [{} for _ in specs]
    hooks = [RunHooks(on_finish=lambda learner, s=s: s.update(learner.state_dict())) for s in states]
    grouped = execute_lockstep(specs, hooks)
    for single, lock, s1, s2 in zip(singles, grouped, single_states, states):
        assert outcome(lock) == outcome(single)
        assert lock.learner_stats["updates"] > 0 and lock.learner_stats["target_syncs"] > 0
        for key in ("network", "target_network", "adam_mean", "adam_sq_mean", "buffer_transitions", "rng"):
            assert torch.equal(s1[key], s2[key]), key


def test_a_group_of_linear_learners_is_its_single_runs_too():
    specs = [RunSpec(algorithm="linear_q", representation="fsr", seed=seed, budget=400, eval_points=2,
                     eval_episodes=3) for seed in (3, 4)]
    assert [outcome(r) for r in execute_lockstep(specs)] == [outcome(execute_run(s)) for s in specs]


def _transitions(rng: np.random.Generator, count: int):
    for _ in range(count):
        obs, nxt = rng.random(11).astype(np.float32), rng.random(11).astype(np.float32)
        obs[6:], nxt[6:] = 0, 0
        obs[6 + rng.integers(5)], nxt[6 + rng.integers(5)] = 1, 1
        reward = 10.0 if rng.random() < 0.05 else 0.0
        yield obs, int(rng.integers(11)), reward, nxt, reward > 0


def test_the_stacked_update_follows_the_reference_update_step_by_step():
    config = DQNConfig(hidden_size=64, learning_starts=40, buffer_size=200, target_update_interval=30,
                       max_grad_norm=0.1, learning_rate=1e-3)
    seeds = [5, 6, 7]
    stacked = StackedDQN(config, seeds)
    reference = [DQNLearner(replace(config, kernels="reference"), seed=s) for s in seeds]
    rng = np.random.default_rng(0)
    clipped = compared = 0
    for step in range(150):
        for k, learner in enumerate(reference):
            transition = next(_transitions(rng, 1))
            stacked.observe(k, *transition)
            learner.observe(*transition)
        stacked.learn()
        if step >= 40:  # every update, compared as it happens
            for k, learner in enumerate(reference):
                view = stacked.learner(k)
                scale = float(learner.network.flat.detach().abs().max())
                assert torch.allclose(view.network.flat, learner.network.flat, rtol=0, atol=2e-5 * scale)
                assert torch.allclose(view.target_network.flat, learner.target_network.flat, rtol=0, atol=2e-5 * scale)
                assert math.isclose(view.last_loss, learner.last_loss, rel_tol=1e-4, abs_tol=1e-7)
                assert math.isclose(view.update.grad_norm, learner.update.grad_norm, rel_tol=1e-4)
                clipped += learner.update.grad_norm > config.max_grad_norm
                compared += 1
    assert 0 < clipped < compared  # clipped updates and unclipped ones were compared
    assert [v.stats["updates"] for v in stacked.views] == [r.stats["updates"] for r in reference]
    assert [v.stats["target_syncs"] for v in stacked.views] == [r.stats["target_syncs"] for r in reference]


def test_stacked_greedy_actions_are_the_networks_argmax():
    config = DQNConfig(hidden_size=32)
    stacked = StackedDQN(config, [0, 1, 2])
    singles = [DQNLearner(config, seed=s) for s in (0, 1, 2)]
    rng = np.random.default_rng(1)
    for obs, *_ in _transitions(rng, 20):
        assert stacked.act([0, 1, 2], [obs] * 3, explore=False) == [s.act(obs, explore=False) for s in singles]


def test_stacked_networks_run_whole_runs_in_the_lockstep_loop():
    specs = [dqn_spec(seed) for seed in (0, 1)]
    streams = [RunStreams.of(s) for s in specs]
    group = StackedDQN(DQNConfig(**DQN_PARAMS), [s.learner_seed for s in streams])
    results = execute_lockstep(specs, group=group)
    singles = [execute_run(s) for s in specs]
    for lock, single in zip(results, singles):
        assert lock.failure is None and len(lock.mean_reward) == 3
        # Counters follow the step count, whatever the floats: as in the single run.
        for key in ("learning_steps", "updates", "target_syncs", "replay_size"):
            assert lock.learner_stats[key] == single.learner_stats[key], key


class _DivergesAt:
    """A run's learner that reports a divergence from a given step on."""

    def __init__(self, learner, step: int):
        self.learner, self.step, self.steps = learner, step, 0

    def __getattr__(self, name):
        return getattr(self.learner, name)

    def observe(self, *transition):
        self.steps += 1
        self.learner.observe(*transition)

    def divergence(self):
        return "the TD loss is nan" if self.steps >= self.step else None


def test_a_diverged_run_fails_alone_and_is_handed_over_at_once():
    specs = [dqn_spec(seed) for seed in (0, 1, 2)]
    streams = [RunStreams.of(s) for s in specs]
    learners = make_group(specs, streams, "cpu").learners
    learners[1] = _DivergesAt(learners[1], 200)
    handed = []
    results = execute_lockstep(specs, group=PerSeedLearners(learners),
                               on_result=lambda k, r: handed.append((k, r.failure)))
    assert handed[0] == (1, "diverged by step 200: the TD loss is nan")
    assert sorted(k for k, _ in handed) == [0, 1, 2]
    assert results[1].failed and math.isnan(results[1].reward_loss)
    singles = [execute_run(specs[k]) for k in (0, 2)]
    assert [outcome(results[k]) for k in (0, 2)] == [outcome(s) for s in singles]


def test_an_interrupt_stops_the_group_but_keeps_the_results_handed_over():
    specs = [dqn_spec(seed) for seed in (0, 1)]
    streams = [RunStreams.of(s) for s in specs]
    learners = make_group(specs, streams, "cpu").learners
    learners[1] = _DivergesAt(learners[1], 200)

    def interrupt(step, mean_reward, success_rate):
        if step >= 400:
            raise KeyboardInterrupt("signal 15")

    handed = []
    with pytest.raises(KeyboardInterrupt):
        execute_lockstep(specs, [RunHooks(on_evaluation=interrupt), RunHooks()],
                         group=PerSeedLearners(learners), on_result=lambda k, r: handed.append(k))
    assert handed == [1]


def test_a_group_holds_runs_of_one_configuration_with_distinct_seeds():
    with pytest.raises(ValueError, match="differ only in their seed"):
        check_group([dqn_spec(0), dqn_spec(1, budget=300)])
    with pytest.raises(ValueError, match="seeds must be distinct"):
        check_group([dqn_spec(0), dqn_spec(0)])
    with pytest.raises(ValueError, match="lockstep.device='tpu' is unknown; allowed: cpu, cuda"):
        make_group([dqn_spec(0)], [RunStreams.of(dqn_spec(0))], "tpu")
    if not torch.cuda.is_available():
        with pytest.raises(ValueError, match="lockstep.device=cuda: torch .* sees no CUDA device"):
            make_group([dqn_spec(0)], [RunStreams.of(dqn_spec(0))], "cuda")


def test_launchers_group_the_unfinished_seeds_of_each_cell():
    from omegaconf import OmegaConf

    from mediated_transfer.sweep.groups import lockstep_groups

    jobs = [[f"seed={s}", f"cell={c}"] for s in range(5) for c in ("none_0", "regular_1")]
    finished = {("none_0", 1), ("regular_1", 0)}

    def config_of(overrides, runs=2, device="cpu"):
        return OmegaConf.create({"seed": 0, "cell": overrides[1].split("=")[1],
                                 "lockstep": {"runs": runs, "device": device}})

    def is_finished(cfg):
        return (cfg.cell, cfg.seed) in finished

    groups = lockstep_groups(jobs, config_of, is_finished)
    named = [[tuple(jobs[i]) for i in g] for g in groups]
    assert named == [
        [("seed=1", "cell=none_0")],  # finished: alone, it only skips
        [("seed=0", "cell=none_0"), ("seed=2", "cell=none_0")],
        [("seed=3", "cell=none_0"), ("seed=4", "cell=none_0")],
        [("seed=0", "cell=regular_1")],
        [("seed=1", "cell=regular_1"), ("seed=2", "cell=regular_1")],
        [("seed=3", "cell=regular_1"), ("seed=4", "cell=regular_1")],
    ]
    # lockstep.runs=null: one run per group on the CPU, all of a cell's unfinished seeds on a GPU.
    cpu = lockstep_groups(jobs, lambda o: config_of(o, None), is_finished)
    assert all(len(g) == 1 for g in cpu)
    gpu = lockstep_groups(jobs, lambda o: config_of(o, None, "cuda"), is_finished)
    assert sorted(len(g) for g in gpu) == [1, 1, 4, 4]


def _sweep(root, *args: str):
    import subprocess
    import sys

    from mediated_transfer.config.compose import CONF_DIR

    result = subprocess.run(
        [sys.executable, "-m", "mediated_transfer", "-m", "experiment=table4_dnn", "scale=smoke",
         "scale.seeds=3", "cell=none_0,regular_1", "tracking=none", f"paths.root={root}",
         "hydra.launcher.n_jobs=2", *args],
        cwd=CONF_DIR.parent, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-3000:]
    return result.stderr + result.stdout


@pytest.mark.slow
def test_a_lockstep_sweep_writes_the_runs_of_a_sweep_without_it_and_resumes(tmp_path):
    from mediated_transfer.config.spec import spec_from_dict, spec_values
    from mediated_transfer.results import RunResult

    def results(root):
        sweep = root / "multirun" / "table4_dnn" / "smoke"
        return {f"{c}/seed={s}": RunResult.read(sweep / c / f"seed={s}")
                for c in ("none_0", "regular_1") for s in range(3)}

    log = _sweep(tmp_path, "lockstep.runs=2")
    assert "none_0: 2 runs in lockstep (seeds 0,1) on cpu" in log
    grouped = results(tmp_path)
    # Each run is the one its stored config gives alone (as a sweep without lockstep runs it).
    single = {k: execute_run(spec_from_dict(spec_values(r.config))) for k, r in grouped.items()}
    assert {k: outcome(r) for k, r in grouped.items()} == {k: outcome(r) for k, r in single.items()}
    # Each run keeps its own folder and record; those computed in a group say so.
    assert grouped["none_0/seed=0"].code["lockstep_runs"] == 2 and grouped["none_0/seed=0"].code["lockstep"]
    assert "lockstep" not in grouped["none_0/seed=2"].code  # the cell's last seed ran alone
    assert all(stale(r) is None for r in grouped.values())
    folder = tmp_path / "multirun" / "table4_dnn" / "smoke" / "regular_1" / "seed=1"
    assert (folder / ".hydra" / "config.yaml").is_file() and (folder / "learner.pt").is_file()
    # Resumed: the missing runs of a cell are grouped, the finished one is only found.
    for seed in (0, 1):
        (tmp_path / "multirun" / "table4_dnn" / "smoke" / "none_0" / f"seed={seed}" / "result.json").unlink()
    log = _sweep(tmp_path, "lockstep.runs=3")
    assert "none_0: 2 runs in lockstep (seeds 0,1) on cpu" in log and "regular_1: 2 runs in lockstep" not in log
    assert {k: outcome(r) for k, r in results(tmp_path).items()} == {k: outcome(r) for k, r in single.items()}
