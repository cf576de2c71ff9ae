"""ALP-GMM after Portelas, Colas, Hofmann and Oudeyer 2019 ("Teacher algorithms for curriculum
learning of Deep RL in continuously parameterized environments", CoRL, Algorithm 1; their code:
github.com/flowersteam/teachDeepRL, teachDRL/teachers/algos/alp_gmm.py), over the target's
distance from O.

A task parameter p is the target distance, normalised to [0, 1] over the whole task space
(``TaskSpace.distances``: the source tasks' nearest to the target annulus' farthest). Every
episode's (p, r), r = 1 if solved else 0, joins a history H; its absolute learning progress is
ALP = |r - r_old|, r_old the reward of the nearest earlier p in H (0 while H holds 5 tasks or
fewer, as their code). The (p, ALP) pairs of the last ``fit_every`` episodes (their window W)
are fit, every ``fit_every`` episodes, by Gaussian mixtures of 2..``k_max`` full-covariance
components (scikit-learn, one EM initialisation), the one of lowest AIC kept. A task: with
probability ``random_share`` p uniform over the space; otherwise a component chosen with
probability proportional to its mean ALP (uniformly if all are 0), p drawn from its marginal
over p and clipped into [0, 1]. Bootstrap: p uniform until the first fit, after ``fit_every``
episodes. Values in conf/strategy/alp_gmm.yaml.

Departures. The reward is ``solved`` (0/1), where their controller maps BipedalWalker's return
linearly onto [0, 1]: the same scale, and indifferent to how a learner's return is shaped. Each
fit gets a fresh seed from the strategy's stream, where theirs reuse one seed; GMMs are refit
from scratch every time (their default, warm_start False). The nearest neighbour is an exact
lookup in a sorted list (a 1-D parameter) where theirs is a buffered k-d tree: the same answer.
Never done: the paper keeps ``random_share`` of the tasks uniform over the whole space, the
target annulus included, to the end, and the target annulus is part of that space; a distance
in it gives a task of the task space at that distance (not None), so that its outcome feeds H.
"""

from __future__ import annotations

import bisect

import numpy as np

from mediated_transfer.transfer import EpisodeOutcome, StrategyContext

MIN_HISTORY = 5
"""ALP is 0 while the history holds this many tasks or fewer (their EmpiricalALPComputer)."""


class AlpGmm:
    """``strategy=alp_gmm`` (conf/strategy/alp_gmm.yaml)."""

    source_tasks = "none"  # tasks are made from the task space: n_source=0
    done = False  # never: a share of tasks stays uniform over the whole space

    def __init__(self, context: StrategyContext, *, fit_every: int, random_share: float, k_max: int):
        if isinstance(k_max, bool) or not isinstance(k_max, int) or k_max < 2:
            raise ValueError(f"strategy.k_max must be an integer >= 2, got {k_max!r}")
        if isinstance(fit_every, bool) or not isinstance(fit_every, int) or fit_every < k_max:
            raise ValueError(f"strategy.fit_every must be an integer >= k_max ({k_max}), got {fit_every!r}")
        if isinstance(random_share, bool) or not isinstance(random_share, (int, float)) \
                or not 0.0 <= random_share <= 1.0:
            raise ValueError(f"strategy.random_share must be a number in [0, 1], got {random_share!r}")
        self.rng, self.space = context.rng, context.task_space
        self.fit_every, self.random_share, self.k_max = fit_every, float(random_share), k_max
        self.low, self.high = self.space.distances
        self.episodes = 0
        self.fits = 0
        self.gmm = None  # the mixture of lowest AIC at the last fit; None: bootstrap
        self._history_p: list[float] = []  # H, sorted by p
        self._history_r: list[float] = []
        self._window: list[tuple[float, float]] = []  # W: (p, ALP) since the last fit
        self._pending: float | None = None

    def sample_p(self) -> float:
        """The next task parameter in [0, 1]."""
        if self.gmm is None or self.rng.random() < self.random_share:
            return float(self.rng.random())
        alp = np.clip(self.gmm.means_[:, 1], 0.0, None)
        probs = alp / alp.sum() if alp.sum() > 0 else np.full(len(alp), 1.0 / len(alp))
        k = self.rng.choice(len(alp), p=probs)
        p = self.rng.normal(self.gmm.means_[k, 0], np.sqrt(self.gmm.covariances_[k, 0, 0]))
        return float(np.clip(p, 0.0, 1.0))

    def next_task(self):
        self._pending = self.sample_p()
        return self.space.sample(self.rng, self.low + self._pending * (self.high - self.low))

    def alp(self, p: float, reward: float) -> float:
        """|r - r_old| against the nearest earlier task of H; then (p, r) joins H."""
        alp = 0.0
        if len(self._history_p) > MIN_HISTORY:
            i = bisect.bisect_left(self._history_p, p)
            near = min((j for j in (i - 1, i) if 0 <= j < len(self._history_p)),
                       key=lambda j: abs(self._history_p[j] - p))
            alp = abs(reward - self._history_r[near])
        i = bisect.bisect_right(self._history_p, p)
        self._history_p.insert(i, p)
        self._history_r.insert(i, reward)
        return alp

    def report(self, outcome: EpisodeOutcome) -> None:
        if outcome.task is None or self._pending is None:  # not a task of ours
            return
        p, self._pending = self._pending, None
        reward = 1.0 if outcome.solved else 0.0
        self._window.append((p, self.alp(p, reward)))
        self.episodes += 1
        if self.episodes % self.fit_every == 0:
            self.fit(np.asarray(self._window))
            self._window = []

    def fit(self, data: np.ndarray) -> None:
        """Mixtures of 2..k_max components on (p, ALP) rows; keep the one of lowest AIC."""
        from sklearn.mixture import GaussianMixture
        from threadpoolctl import threadpool_limits

        best, best_aic = None, np.inf
        with threadpool_limits(1):
            for k in range(2, self.k_max + 1):
                gmm = GaussianMixture(k, covariance_type="full", n_init=1,
                                      random_state=int(self.rng.integers(2**31))).fit(data)
                aic = gmm.aic(data)
                if aic < best_aic:
                    best, best_aic = gmm, aic
        self.gmm = best
        self.fits += 1
