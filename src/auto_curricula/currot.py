"""CURROT after Klink et al. 2022 ("Curriculum Reinforcement Learning via Constrained Optimal
Transport", ICML), as the authors' main-branch code (github.com/psclklnk/currot) does it, over one
context: the target's distance from O.

The training distribution is a set of ``n_particles`` particles (target distances), at first
uniform over the source distances (the easy tasks, the target within reach). Each episode
starts from a task at a particle drawn uniformly (plus their 1e-3-of-the-range jitter). Every
``update_every`` episodes the particles move: each is coupled to a sample of the target
distribution mu* (the target annulus, area-uniform) by optimal transport, which in one dimension
is the sorted coupling, and goes to the point nearest its sample among the candidates within
``epsilon`` of it (the trust region, per particle as in their code) whose estimated success rate
is >= ``delta`` (the performance constraint); a particle with no such candidate goes to the
candidate of highest estimated success. The estimate is their Nadaraya-Watson regression of
success (``outcome.solved``: the success reward is a return threshold here) on the context, with
their Gaussian kernel of length scale 0.3 * epsilon. Never done: the distribution itself becomes
mu* once the learner succeeds there; its target-annulus episodes are tasks at those distances.

Departures from their code, and why:
- Candidates are a grid of 2 * STEPS + 1 points over [p - epsilon, p + epsilon] plus the direct
  step toward the coupled sample, not 100 random points of a (half) ball: the same optimum in 1-D,
  without sampling noise.
- A particle below delta walks toward higher estimated success, epsilon at most per update. Their
  code first swaps such particles for nearby contexts of its success buffer (a jump of any
  length); the paper's trust region W(p, p_old) <= epsilon forbids jumps.
- The estimate is fit on the last 2 * n_particles outcomes, each counted once, with the full
  kernel (in log space, so that it points toward success however far). Theirs is fit on up to
  n successes (those best matching mu*) plus the last n failures, a kernel cut at three length
  scales with a 10-nearest fallback: capping successes and failures apart overstates a low
  success rate (n old successes against the last n failures).
- No first phase before the success buffer reaches delta (their wide exploration noise): here
  the initial distribution is already easy, and particles stay put until success is seen.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from mediated_transfer.transfer import EpisodeOutcome, StrategyContext

STEPS = 10  # candidates on each side of a particle, within its trust region


def _logsumexp(values: np.ndarray) -> np.ndarray:
    """log(sum(exp(values))) over the last axis; -inf where every value is -inf."""
    top = np.max(values, axis=-1)
    top = np.where(np.isfinite(top), top, 0.0)
    with np.errstate(divide="ignore"):
        return np.log(np.sum(np.exp(values - top[..., None]), axis=-1)) + top


class Currot:
    """``strategy=currot`` (conf/strategy/currot.yaml)."""

    source_tasks = "none"  # particles are made from the task space: n_source=0
    done = False  # the particles converge to the target distribution themselves

    def __init__(self, context: StrategyContext, *, n_particles: int, delta: float, epsilon: float,
                 update_every: int):
        for key, value, least in (("n_particles", n_particles, 2), ("update_every", update_every, 1)):
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise ValueError(f"strategy.{key} must be an integer >= {least}, got {value!r}")
        if isinstance(delta, bool) or not isinstance(delta, (int, float)) or not 0 < delta <= 1:
            raise ValueError(f"strategy.delta must be a success rate in (0, 1], got {delta!r}")
        if isinstance(epsilon, bool) or not isinstance(epsilon, (int, float)) or not 0 < epsilon < 1e6:
            raise ValueError(f"strategy.epsilon must be a number > 0, got {epsilon!r}")
        self.rng, self.space = context.rng, context.task_space
        self.n_particles, self.update_every = n_particles, update_every
        self.delta, self.epsilon = float(delta), float(epsilon)
        self.bandwidth = 0.3 * self.epsilon  # their kernel length scale
        self.low, self.high = self.space.distances
        self.noise = 1e-3 * (self.high - self.low)  # their sampler's jitter
        self._particles = self.rng.uniform(*self.space.source_distances, size=n_particles)
        self._contexts: deque[float] = deque(maxlen=2 * n_particles)
        self._solved: deque[bool] = deque(maxlen=2 * n_particles)
        self._since_update = 0
        self.updates = 0
        steps = np.arange(1, STEPS + 1) / STEPS  # offsets by distance from the particle: on a tie
        self._offsets = self.epsilon * np.concatenate(([0.0], np.ravel([steps, -steps], order="F")))

    @property
    def particles(self) -> np.ndarray:
        """The current training distribution (a read-only copy)."""
        particles = self._particles.copy()
        particles.flags.writeable = False
        return particles

    def next_task(self):
        particle = self._particles[self.rng.integers(self.n_particles)]
        distance = float(np.clip(particle + self.rng.uniform(-self.noise, self.noise), self.low, self.high))
        return self.space.sample(self.rng, distance)

    def report(self, outcome: EpisodeOutcome) -> None:
        if outcome.task is None:  # not one of ours
            return
        self._contexts.append(outcome.task.target_distance)
        self._solved.append(bool(outcome.solved))
        self._since_update += 1
        if self._since_update >= self.update_every:
            self._since_update = 0
            self._update()

    def log_success(self, distances) -> np.ndarray:
        """log of the estimated success rate at ``distances`` (Nadaraya-Watson, Gaussian kernel)."""
        distances = np.asarray(distances, dtype=float)
        contexts, solved = np.asarray(self._contexts), np.asarray(self._solved, dtype=bool)
        logits = -0.5 * np.square((distances[..., None] - contexts) / self.bandwidth)
        return _logsumexp(np.where(solved, logits, -np.inf)) - _logsumexp(logits)

    def _update(self) -> None:
        low, high = self.space.target_distances
        samples = np.sort(np.sqrt(self.rng.uniform(low * low, high * high, size=self.n_particles)))
        particles = self._particles
        ranks = np.argsort(np.argsort(particles, kind="stable"), kind="stable")
        goals = samples[ranks]  # the sorted coupling: optimal transport in one dimension
        direct = np.clip(goals, particles - self.epsilon, particles + self.epsilon)
        candidates = np.column_stack((particles[:, None] + self._offsets, direct))
        candidates = np.clip(candidates, self.low, self.high)  # clipping stays in the trust region
        log_success = self.log_success(candidates)
        feasible = log_success >= np.log(self.delta)
        nearest = np.argmin(np.where(feasible, np.abs(candidates - goals[:, None]), np.inf), axis=1)
        choice = np.where(feasible.any(axis=1), nearest, np.argmax(log_success, axis=1))
        self._particles = candidates[np.arange(self.n_particles), choice]
        self.updates += 1
