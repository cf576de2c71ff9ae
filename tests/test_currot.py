"""CURROT (Klink et al. 2022, auto_curricula/currot.py) on scripted outcomes: the particles reach
the target annulus at the trust region's pace, keep to where success is estimated, never move
more than epsilon per update; parameters, determinism and the YAML."""

import math
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf

import auto_curricula
from auto_curricula.currot import Currot
from mediated_transfer.env.task_space import TaskSpace
from mediated_transfer.transfer import EpisodeOutcome, StrategyContext

CONF = Path(auto_curricula.__file__).parent / "conf"
SPACE = TaskSpace()
TARGET_FROM, TARGET_TO = SPACE.target_distances
PAPER = dict(n_particles=100, delta=0.6, epsilon=0.75, update_every=20)


def context(seed=0):
    return StrategyContext(rng=np.random.default_rng(seed))


def outcome(task, solved):
    return EpisodeOutcome(task, bool(solved), 10.0 if solved else 0.0, 1, 1)


def play(strategy, solves, updates):
    """``updates`` updates' worth of episodes; the particles before and after each update, and
    the distances of the episodes' tasks."""
    history, distances = [strategy.particles.copy()], []
    for _ in range(updates):
        for _ in range(strategy.update_every):
            task = strategy.next_task()
            assert task is not None
            distances.append(task.target_distance)
            strategy.report(outcome(task, solves(task.target_distance)))
        history.append(strategy.particles.copy())
    return np.array(history), np.array(distances)


def test_the_particles_start_on_the_source_distances_and_episodes_are_drawn_from_them():
    strategy = Currot(context(seed=1), **PAPER)
    start = strategy.particles
    assert start.shape == (100,) and SPACE.source_distances[0] <= start.min() <= start.max() <= SPACE.source_distances[1]
    with pytest.raises(ValueError):
        start[0] = 3.0  # read-only
    _, distances = play(strategy, lambda d: False, 1)
    # Every episode within the sampler's jitter (1e-3 of the range) of a particle.
    assert np.min(np.abs(distances[:, None] - start[None, :]), axis=1).max() <= 1e-3 * 10.5 + 1e-9


def test_a_learner_that_solves_everything_brings_the_median_into_the_target_annulus_at_epsilon_per_update():
    strategy = Currot(context(seed=0), **PAPER)
    start = np.sort(strategy.particles)
    eps = PAPER["epsilon"]
    # All estimates are 1: each particle steps eps toward its coupled target sample (>= 10.5) until
    # within eps of it. The median (mean of the 50th and 51st) is in the annulus once the 50th is:
    # after exactly ceil((10.5 - p_50) / eps) updates, and the 51st at the earliest after
    # ceil((10.5 - p_51) / eps). The front particle enters after ceil((10.5 - p_max) / eps), the
    # last after ceil((10.5 - p_min) / eps) (the brief's (10.5 - source max) / eps, per rank).
    first, latest = (math.ceil((TARGET_FROM - start[i]) / eps) for i in (50, 49))
    everyone = math.ceil((TARGET_FROM - start[0]) / eps)
    assert latest <= 8  # the median starts near 5.5: about 5 / 0.75 updates, 140 episodes
    history, _ = play(strategy, lambda d: True, everyone + 5)
    inside = [TARGET_FROM <= np.median(p) <= TARGET_TO for p in history]
    entered = inside.index(True)
    assert first <= entered <= latest
    assert all(inside[latest:])  # and stays
    assert math.ceil((TARGET_FROM - start[-1]) / eps) == next(
        k for k, p in enumerate(history) if p.max() >= TARGET_FROM)
    assert history[everyone].min() >= TARGET_FROM and history[everyone - 1].min() < TARGET_FROM
    assert np.all(history[everyone:] <= TARGET_TO)


@pytest.mark.parametrize("edge", [4.0, 6.0])
def test_the_particles_keep_to_where_success_is_estimated(edge):
    """A learner that solves tasks nearer than ``edge`` only: the particles overshoot by at most one
    trust region, fail there, and walk back; from then on none is beyond edge + epsilon."""
    strategy = Currot(context(seed=2), **PAPER)
    eps = PAPER["epsilon"]
    history, distances = play(strategy, lambda d: d < edge, 300)  # 6,000 episodes
    settled = math.ceil((SPACE.source_distances[1] - edge) / eps) + 5  # the farthest walks back at eps
    assert history[settled:].max() <= edge + eps
    assert np.median(history[-1]) == pytest.approx(edge, abs=0.25)  # at the frontier, not behind it
    # The particles sit where the estimated success rate is delta: so do the episodes' outcomes.
    assert np.mean(distances[-2000:] < edge) >= PAPER["delta"] - 0.05


def test_without_any_success_the_particles_stay_on_the_initial_distribution():
    strategy = Currot(context(seed=3), **PAPER)
    history, _ = play(strategy, lambda d: False, 20)
    np.testing.assert_array_equal(history[-1], history[0])


@pytest.mark.parametrize("learner", ["noisy", "edge"])
def test_no_particle_moves_more_than_epsilon_in_an_update(learner):
    rng = np.random.default_rng(7)
    solves = {"noisy": lambda d: rng.random() < np.clip((12.5 - d) / 8, 0, 1), "edge": lambda d: d < 7.0}[learner]
    params = {**PAPER, "epsilon": 0.4, "update_every": 10}
    strategy = Currot(context(seed=5), **params)
    history, _ = play(strategy, solves, 200)
    steps = np.abs(np.diff(history, axis=0))
    assert steps.max() <= 0.4 + 1e-9
    assert steps.max() >= 0.4 - 1e-9  # the bound is reached: the particles move
    assert strategy.updates == 200


@pytest.mark.parametrize("key, value, message", [
    ("n_particles", 1, "strategy.n_particles must be an integer >= 2"),
    ("n_particles", 100.0, "strategy.n_particles must be an integer >= 2"),
    ("update_every", 0, "strategy.update_every must be an integer >= 1"),
    ("update_every", True, "strategy.update_every must be an integer >= 1"),
    ("delta", 0.0, r"strategy.delta must be a success rate in \(0, 1\]"),
    ("delta", 10.0, r"strategy.delta must be a success rate in \(0, 1\]"),
    ("delta", "0.6", r"strategy.delta must be a success rate in \(0, 1\]"),
    ("epsilon", 0, "strategy.epsilon must be a number > 0"),
    ("epsilon", -0.5, "strategy.epsilon must be a number > 0"),
    ("epsilon", float("nan"), "strategy.epsilon must be a number > 0"),
])
def test_bad_parameters_are_refused_naming_the_key(key, value, message):
    with pytest.raises(ValueError, match=message):
        Currot(context(), **{**PAPER, key: value})


def test_the_same_seed_gives_the_same_curriculum():
    runs = [play(Currot(context(seed=4), **PAPER), lambda d: d < 8.0, 30) for _ in range(2)]
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    other = play(Currot(context(seed=5), **PAPER), lambda d: d < 8.0, 30)
    assert not np.array_equal(other[0][-1], runs[0][0][-1])


def test_the_yaml_keys_are_the_constructors_and_the_cell_selects_it():
    node = OmegaConf.to_container(OmegaConf.load(CONF / "strategy" / "currot.yaml"))
    assert node.pop("_target_") == "auto_curricula.currot.Currot" and node.pop("name") == "currot"
    assert node == PAPER
    strategy = Currot(context(), **node)
    assert strategy.source_tasks == "none" and strategy.done is False
    cell = OmegaConf.load(CONF / "cell" / "currot_0.yaml")
    assert list(cell.defaults) == [{"override /strategy": "currot"}, {"override /n_source": "0"}]
