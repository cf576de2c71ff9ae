"""The RBF and FSR representations: feature counts, hand-computed states, sparse == dense."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mediated_transfer.env import sample_task
from mediated_transfer.learners import (
    FSRConfig,
    FSRRepresentation,
    LinearQConfig,
    LinearQLearner,
    RBFConfig,
    RBFRepresentation,
)

M1, M2, M3, T, O = range(5)


def observation(distances, active: int) -> np.ndarray:
    obs = np.zeros(11)
    obs[:6] = distances
    obs[6 + active] = 1.0
    return obs


def dense(rep, obs) -> np.ndarray:
    index, value = rep.features(obs)
    phi = np.zeros(rep.num_features)
    phi[index] = value
    return phi


def realistic_states(n: int, seed: int) -> list[np.ndarray]:
    """Task start states of both scenarios, perturbed as moves would, with random picks."""
    rng = np.random.default_rng(seed)
    states = []
    for i in range(n):
        s = sample_task("source" if i % 2 else "target", rng).sensor_vector()
        s[:6] = np.abs(s[:6] + rng.normal(0.0, 2.0, 6))
        s[6:] = 0.0
        s[6 + rng.integers(5)] = 1.0
        states.append(s)
    return states


# --- RBF --------------------------------------------------------------------------------------


def test_rbf_has_the_papers_13829_features():
    rep = RBFRepresentation()
    assert rep.num_gaussians == 6**3 * 4**3 == 13824
    assert rep.num_features == 13829


def test_rbf_centres_follow_rlpy_grid_with_borders():
    rep = RBFRepresentation()
    for d in range(3):
        np.testing.assert_allclose(rep.centres_per_dim[d], [0, 4, 8, 12, 16, 20])
    for d in range(3, 6):
        np.testing.assert_allclose(rep.centres_per_dim[d], [0, 4, 8, 12])
    # Feature order: the first |MiT| dimension varies slowest (RLPy's perms order).
    centres = rep.centres()
    assert centres.shape == (13824, 6)
    np.testing.assert_allclose(centres[0], [0, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(centres[1], [0, 0, 0, 0, 0, 4])
    np.testing.assert_allclose(centres[-1], [20, 20, 20, 12, 12, 12])


# Strides of the row-major grid (6, 6, 6, 4, 4, 4): feature index of centre indices k.
STRIDES = (6 * 6 * 4 * 4 * 4, 6 * 4 * 4 * 4, 4 * 4 * 4, 4 * 4, 4, 1)


def grid_index(k) -> int:
    return sum(ki * s for ki, s in zip(k, STRIDES))


def test_rbf_raw_gaussians_on_a_hand_computed_state():
    rep = RBFRepresentation(RBFConfig(normalize=False))
    # Exactly on the centre (4, 8, 12 | 0, 4, 8), M3 active.
    obs = observation([4, 8, 12, 0, 4, 8], M3)
    phi = dense(rep, obs)
    centre = grid_index((1, 2, 3, 0, 1, 2))
    assert centre == 3270
    assert phi[centre] == pytest.approx(1.0)
    # One centre further in the first dimension: (4 - 8)^2 / 2 = 8.
    assert phi[grid_index((2, 2, 3, 0, 1, 2))] == pytest.approx(math.exp(-8))
    # One step in two dimensions, exp(-(16 + 16) / 2) = 1.1e-7, is below the 1e-5 cutoff:
    # dropped from the sparse features, present in the dense reference.
    two_steps = grid_index((1, 1, 3, 0, 1, 3))
    assert phi[two_steps] == 0.0
    assert rep.dense_features(obs)[two_steps] == pytest.approx(math.exp(-16))
    # The binary part is the one-hot as it is: only M3.
    np.testing.assert_array_equal(phi[13824:], [0, 0, 1, 0, 0])


def test_rbf_halfway_between_centres_gives_two_equal_gaussians():
    rep = RBFRepresentation(RBFConfig(normalize=False))
    obs = observation([2, 8, 12, 0, 4, 8], O)  # first distance halfway between 0 and 4
    phi = dense(rep, obs)
    left, right = grid_index((0, 2, 3, 0, 1, 2)), grid_index((1, 2, 3, 0, 1, 2))
    assert phi[left] == pytest.approx(math.exp(-2))
    assert phi[right] == pytest.approx(math.exp(-2))
    assert phi[13828] == 1.0


def test_rbf_normalised_is_the_gaussian_over_the_separable_grid_sum():
    rep = RBFRepresentation()  # normalize=True by default
    s = np.array([4, 8, 12, 0, 4, 8.0])
    phi = dense(rep, observation(s, M1))
    # The sum over a tensor-product grid of separable Gaussians is a product of 1-D sums.
    total = 1.0
    for d in range(6):
        total *= sum(math.exp(-((s[d] - c) ** 2) / 2) for c in rep.centres_per_dim[d])
    assert phi[3270] == pytest.approx(1.0 / total, rel=1e-12)
    assert rep.dense_features(observation(s, M1))[:13824].sum() == pytest.approx(1.0, abs=1e-12)
    # The sparse features are the dense ones minus Gaussians below the cutoff: a tiny mass.
    assert 1.0 - 1e-4 < phi[:13824].sum() <= 1.0
    np.testing.assert_array_equal(phi[13824:], [1, 0, 0, 0, 0])


def test_rbf_keeps_only_a_few_gaussians():
    rep = RBFRepresentation()
    counts = [len(rep.features(s)[0]) for s in realistic_states(200, seed=1)]
    # Centres 4 sigma apart and a 1e-5 cutoff leave at most 3 centres per dimension and,
    # after the product cutoff, well under a hundred Gaussians (plus the one active bit).
    assert max(counts) <= 3**6 + 1
    assert 5 < np.mean(counts) < 100


@pytest.mark.parametrize("normalize", [True, False])
def test_rbf_sparse_q_values_match_the_dense_computation(normalize):
    """Tolerance: ||phi_dense - phi_sparse||_1 <= 3e-4 (cutoff 1e-5: 4e-5 on average, 1.2e-4
    at most over 1500 states), so |Q_sparse - Q_dense| <= 3e-4 * max|theta| for every action."""
    rep = RBFRepresentation(RBFConfig(normalize=normalize))
    learner = LinearQLearner(LinearQConfig(), rep)
    rng = np.random.default_rng(2)
    learner.theta[:] = rng.uniform(-10, 10, learner.theta.shape)
    bound = 3e-4 * np.abs(learner.theta).max()
    for s in realistic_states(150, seed=3):
        phi_dense = rep.dense_features(s)
        assert np.abs(phi_dense - dense(rep, s)).sum() <= 3e-4
        np.testing.assert_allclose(learner.q_values(s), learner.theta @ phi_dense, rtol=0, atol=bound)


def test_rbf_far_outside_the_grid_stays_finite_and_normalised():
    rep = RBFRepresentation()
    phi = dense(rep, observation([36, 36, 36, 18, 18, 18], T))  # the walls' bounds
    assert np.all(np.isfinite(phi))
    assert phi[:13824].sum() == pytest.approx(1.0)
    assert phi[grid_index((5, 5, 5, 3, 3, 3))] == phi[:13824].max()  # the corner centre
    np.testing.assert_allclose(rep.dense_features(observation([36, 36, 36, 18, 18, 18], T)), phi, atol=1e-12)


def test_rbf_cutoff_zero_is_the_dense_vector():
    rep = RBFRepresentation(RBFConfig(cutoff=0.0))
    s = observation([3.3, 7.1, 15.2, 2.2, 9.9, 5.0], M2)
    assert len(rep.features(s)[0]) == 13824 + 1
    np.testing.assert_allclose(dense(rep, s), rep.dense_features(s), rtol=1e-12, atol=1e-300)


# --- FSR --------------------------------------------------------------------------------------


def test_fsr_has_the_papers_310_features():
    assert FSRRepresentation().num_features == 6 * 50 + 5 * 2 == 310


def test_fsr_bins_a_hand_computed_state():
    rep = FSRRepresentation()  # |MiT| bins of 24/50 = 0.48, |MiO| bins of 12/50 = 0.24
    obs = observation([0.0, 1.0, 30.0, 12.0, 6.1, -1.0], T)
    index, value = rep.features(obs)
    expected = [
        0 * 50 + 0,    # |M1T| = 0      -> bin 0
        1 * 50 + 2,    # |M2T| = 1.0    -> floor(2.08) = 2
        2 * 50 + 49,   # |M3T| = 30     -> clipped into the last bin
        3 * 50 + 49,   # |M1O| = 12     -> the top edge falls into the last bin
        4 * 50 + 25,   # |M2O| = 6.1    -> floor(25.4) = 25
        5 * 50 + 0,    # |M3O| = -1     -> clipped into bin 0
        300, 302, 304,  # M1, M2, M3 inactive: their "0" bins
        307,           # T active: its "1" bin
        308,           # O inactive
    ]
    assert index.tolist() == expected
    assert value.tolist() == [1.0] * 11


def test_fsr_has_exactly_one_active_feature_per_entry():
    rep = FSRRepresentation()
    for s in realistic_states(100, seed=4):
        index, value = rep.features(s)
        assert len(index) == 11 and np.all(value == 1.0)
        owner = np.where(index < 300, index // 50, 6 + (index - 300) // 2)
        assert sorted(owner.tolist()) == list(range(11))


@pytest.mark.parametrize("rep", [RBFRepresentation(), FSRRepresentation()], ids=["rbf", "fsr"])
def test_active_indices_are_strictly_ascending(rep):
    # The learner merges phi(s, a) into its index-sorted trace in one pass: it relies on this.
    for s in realistic_states(100, seed=5):
        index, _ = rep.features(s)
        assert np.all(np.diff(index) > 0)


# --- bad input ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, key",
    [
        ({"tool_target_bins": 0}, "representation.tool_target_bins"),
        ({"tool_origin_bins": 2.5}, "representation.tool_origin_bins"),
        ({"tool_target_low": 5.0, "tool_target_high": 5.0}, "representation.tool_target_low"),
        ({"tool_origin_high": math.inf}, "representation.tool_origin_low"),
        ({"sigma": 0.0}, "representation.sigma"),
        ({"cutoff": 1.0}, "representation.cutoff"),
        ({"cutoff": -1e-3}, "representation.cutoff"),
        ({"sigma": "1"}, "representation.sigma"),
        ({"normalize": 1}, "representation.normalize"),
    ],
)
def test_rbf_config_rejects_bad_values(kwargs, key):
    with pytest.raises(ValueError, match=key):
        RBFConfig(**kwargs)


@pytest.mark.parametrize(
    "kwargs, key",
    [
        ({"distance_bins": 0}, "representation.distance_bins"),
        ({"distance_bins": True}, "representation.distance_bins"),
        ({"tool_target_low": 30.0}, "representation.tool_target_low"),
        ({"tool_origin_low": math.nan}, "representation.tool_origin_low"),
    ],
)
def test_fsr_config_rejects_bad_values(kwargs, key):
    with pytest.raises(ValueError, match=key):
        FSRConfig(**kwargs)


@pytest.mark.parametrize("rep", [RBFRepresentation(), FSRRepresentation()], ids=["rbf", "fsr"])
def test_bad_observations_raise(rep):
    with pytest.raises(ValueError, match="shape"):
        rep.features(np.zeros(6))
    bad = observation([1, 2, 3, 4, 5, 6], O)
    bad[2] = np.nan
    with pytest.raises(ValueError, match="finite"):
        rep.features(bad)
