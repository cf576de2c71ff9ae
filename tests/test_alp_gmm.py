"""ALP-GMM (Portelas et al. 2019, auto_curricula/alp_gmm.py) on scripted outcomes, against the
paper's Algorithm 1 and the authors' code: bootstrap, ALP, fits, the random share, parameters."""

from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf
from scipy import stats

import auto_curricula
from auto_curricula.alp_gmm import AlpGmm
from mediated_transfer.env.task_space import TaskSpace
from mediated_transfer.transfer import EpisodeOutcome, StrategyContext

CONF = Path(auto_curricula.__file__).parent / "conf"
SPACE = TaskSpace()
LOW, HIGH = SPACE.distances
PAPER = dict(fit_every=250, random_share=0.2, k_max=10)
BAND = (6.0, 8.0)  # where the scripted learner makes progress


def context(seed=0):
    return StrategyContext(rng=np.random.default_rng(seed))


def outcome(task, solved):
    return EpisodeOutcome(task, bool(solved), 10.0 if solved else 0.0, 1, 1)


def banded_learner(seed, ramp=6000):
    """Solves every task nearer than the band, none farther; in the band its success
    probability rises with its episode count (learning progress only there)."""
    rng = np.random.default_rng(seed)

    def solves(distance, episode):
        if distance < BAND[0]:
            return True
        if distance > BAND[1]:
            return False
        return rng.random() < min(1.0, episode / ramp)

    return solves


def play(strategy, solves, episodes):
    chosen = []
    for episode in range(episodes):
        task = strategy.next_task()
        chosen.append(task.target_distance)
        strategy.report(outcome(task, solves(task.target_distance, episode)))
    return np.array(chosen)


def test_before_the_first_fit_the_draws_are_uniform_over_the_whole_space_whatever_the_outcomes():
    runs = []
    for solved in (True, False):
        strategy = AlpGmm(context(seed=1), **{**PAPER, "fit_every": 2000})
        runs.append(play(strategy, lambda d, e: solved, 1999))
        assert strategy.gmm is None and strategy.fits == 0 and not strategy.done
        strategy.report(outcome(strategy.next_task(), solved))  # the 2000th episode: the first fit
        assert strategy.fits == 1 and strategy.gmm is not None
    np.testing.assert_array_equal(runs[0], runs[1])
    assert runs[0].min() >= LOW and runs[0].max() <= HIGH
    assert (runs[0] >= SPACE.target_distances[0]).any()  # the target annulus is in the space
    assert stats.kstest(runs[0], stats.uniform(loc=LOW, scale=HIGH - LOW).cdf).pvalue > 0.01


def test_alp_is_the_reward_change_against_the_nearest_earlier_task_after_five_tasks():
    strategy = AlpGmm(context(), **PAPER)
    # The first six tasks get ALP 0 (their code: ALP once the history holds more than 5).
    assert [strategy.alp(p, r) for p, r in [(0.1, 1), (0.3, 0), (0.5, 1), (0.7, 0), (0.9, 1), (0.2, 1)]] == [0] * 6
    assert strategy.alp(0.32, 1.0) == 1.0  # nearest: 0.3, reward 0
    assert strategy.alp(0.33, 1.0) == 0.0  # nearest: 0.32 (just added), reward 1
    assert strategy.alp(0.86, 0.0) == 1.0  # nearest: 0.9, reward 1
    assert strategy.alp(0.0, 0.0) == 1.0  # nearest: 0.1, reward 1 (an end of the space)


def test_after_a_few_fits_most_gmm_draws_fall_in_the_band_of_learning_progress():
    strategy = AlpGmm(context(seed=2), **PAPER)
    solves = banded_learner(seed=2)
    play(strategy, solves, 2500)  # 10 fits
    assert strategy.fits == 10
    later = play(strategy, solves, 1000)
    in_band = np.mean((later >= BAND[0]) & (later <= BAND[1]))
    uniform_in_band = (BAND[1] - BAND[0]) / (HIGH - LOW)
    # Of the GMM's (non-random) draws, the share in the band: most of them (uniform: 19 %).
    gmm_in_band = (in_band - PAPER["random_share"] * uniform_in_band) / (1 - PAPER["random_share"])
    assert gmm_in_band > 0.7
    # The components chosen: those of high mean ALP lie in the band (normalised p).
    means = strategy.gmm.means_
    hot = means[means[:, 1] > 0.2, 0] * (HIGH - LOW) + LOW
    assert len(hot) and np.all((hot > BAND[0] - 0.5) & (hot < BAND[1] + 0.5))


def narrow_fit(strategy, centre=0.5, width=0.005):
    """A GMM fit on (p, ALP) pairs all in a narrow band of p around ``centre``."""
    rng = np.random.default_rng(0)
    p = rng.normal(centre, width, size=250)
    alp = (rng.random(250) < 0.6).astype(float)
    strategy.fit(np.column_stack([p, alp]))


@pytest.mark.parametrize("share", [0.0, 0.2, 0.5, 1.0])
def test_a_random_share_of_the_draws_is_uniform_over_the_space(share):
    strategy = AlpGmm(context(seed=3), **{**PAPER, "random_share": share})
    narrow_fit(strategy)
    n = 5000
    drawn = np.array([strategy.next_task().target_distance for _ in range(n)])
    lo, hi = LOW + 0.45 * (HIGH - LOW), LOW + 0.55 * (HIGH - LOW)  # the band: +- 10 widths
    outside = ~((drawn >= lo) & (drawn <= hi))
    expected = share * 0.9  # uniform draws outside a tenth of the space
    assert outside.mean() == pytest.approx(expected, abs=3 * np.sqrt(expected * (1 - expected) / n) + 1e-9)
    if share == 1.0:
        assert stats.kstest(drawn, stats.uniform(loc=LOW, scale=HIGH - LOW).cdf).pvalue > 0.01
    elif share > 0:  # the random ones outside the band: uniform there too
        below = drawn[drawn < lo]
        assert stats.kstest(below, stats.uniform(loc=LOW, scale=lo - LOW).cdf).pvalue > 0.01


@pytest.mark.parametrize("key, value, message", [
    ("k_max", 1, "strategy.k_max must be an integer >= 2"),
    ("k_max", 2.5, "strategy.k_max must be an integer >= 2"),
    ("fit_every", 5, r"strategy.fit_every must be an integer >= k_max \(10\)"),
    ("fit_every", True, "strategy.fit_every must be an integer"),
    ("fit_every", 250.0, "strategy.fit_every must be an integer"),
    ("random_share", 1.5, r"strategy.random_share must be a number in \[0, 1\]"),
    ("random_share", -0.1, r"strategy.random_share must be a number in \[0, 1\]"),
    ("random_share", "0.2", r"strategy.random_share must be a number in \[0, 1\]"),
])
def test_bad_parameters_are_refused_naming_the_key(key, value, message):
    with pytest.raises(ValueError, match=message):
        AlpGmm(context(), **{**PAPER, key: value})


def test_the_same_seed_gives_the_same_curriculum():
    runs = []
    for _ in range(2):
        strategy = AlpGmm(context(seed=4), **{**PAPER, "fit_every": 100, "k_max": 4})
        runs.append((play(strategy, banded_learner(seed=4, ramp=600), 600), strategy.gmm.means_))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    other = play(AlpGmm(context(seed=5), **PAPER), banded_learner(seed=4), 10)
    assert not np.array_equal(other, runs[0][0][:10])


def test_the_yaml_keys_are_the_constructors_and_the_cell_selects_it():
    node = OmegaConf.to_container(OmegaConf.load(CONF / "strategy" / "alp_gmm.yaml"))
    assert node.pop("_target_") == "auto_curricula.alp_gmm.AlpGmm" and node.pop("name") == "alp_gmm"
    assert node == PAPER
    assert AlpGmm(context(), **node).fit_every == 250
    cell = OmegaConf.load(CONF / "cell" / "alp_gmm_0.yaml")
    assert list(cell.defaults) == [{"override /strategy": "alp_gmm"}, {"override /n_source": "0"}]


def test_a_run_through_the_strategy_door_fits_and_hears_every_episode():
    from mediated_transfer.run import RunSpec, execute_run

    spec = RunSpec(strategy="alp_gmm", strategy_target="auto_curricula.alp_gmm.AlpGmm",
                   strategy_params={"fit_every": 20, "random_share": 0.2, "k_max": 3},
                   budget=3000, eval_points=2, eval_episodes=2)
    result = execute_run(spec.validate())
    from mediated_transfer.provenance import code_version

    assert result.strategy == "alp_gmm" and code_version(spec)["plugins"][0]["target"] == spec.strategy_target
    assert sum(result.choices["episodes"]) > 20  # past the bootstrap: at least one fit
