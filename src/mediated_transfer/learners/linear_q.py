"""Epsilon-greedy linear Q(lambda) with Boyan learning-rate decay, as in RLPy's ``Q_Learning``.

Q(s, a) = theta_a . phi(s): copy-paste state-action features (Lagoudakis & Parr), one weight
block per action. One learning step on (s, a, r, s'):

    delta = r + gamma * max_a' Q(s', a') - Q(s, a)       (phi(s') = 0 when s' is terminal)
    e     = min(gamma * lambda * e + phi(s, a), 1)       (accumulating trace, clipped at 1)
    theta = theta + alpha * delta * e
    alpha = alpha_0 * (N0 + 1) / (N0 + (episode + 1) ** 1.1) / ||phi(s)||_1   (Boyan)

Traces are zeroed at the end of an episode and are not cut after exploratory actions (RLPy's
naive Q(lambda)). An update that would make a weight non-finite is rolled back, counted in
``stats["rollbacks"]`` and warned about once.

Sparsity: phi(s) has a few dozen active RBF features or 11 FSR features, so the learner only
ever touches those weights. The trace is a list of (weight index, value) pairs kept sorted by
index; one sequential pass merges the decayed trace with phi(s, a), drops old entries that
decayed to ``trace_cutoff`` (their remaining effect is below cutoff / (1 - gamma * lambda) of
one update) and applies the update, so a step costs O(trace length + active features), never
O(13829 * 11), and walks the weights in memory order.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import asdict, dataclass, fields
from typing import Any, Protocol

import numpy as np
from numba import njit

from ..mapping import config_from_mapping
from .rng_state import restore_rng_state, rng_state_words

LEARNING_RATE_DECAYS = ("boyan", "boyan_const", "const")


_DIVERGENCE_MIN_UPDATES = 1000  # fewer: a few early rollbacks are no verdict


@dataclass(frozen=True)
class LinearQConfig:
    """Hyperparameters of linear Q(lambda). Defaults are PROVISIONAL (RLPy's tuned
    ``examples/cartpole2d/rbfs.py`` Q_Learning experiment and its domain's gamma) until the
    project's tuning publishes its own Table I."""

    epsilon: float = 0.1
    """Exploration: probability of a uniformly random action (RLPy eGreedy examples: 0.1)."""
    lambda_: float = 0.75
    """Eligibility-trace decay lambda (RLPy cartpole2d RBF example: 0.75)."""
    gamma: float = 0.95
    """Discount factor (RLPy's InfCartPoleBalance domain: 0.95)."""
    alpha0: float = 0.7
    """Initial learning rate alpha_0 (RLPy cartpole2d RBF example: 0.7)."""
    boyan_n0: float = 5000.0
    """Boyan decay constant N0: the rate halves after about N0 ** (1/1.1) episodes. RLPy's 753
    decayed too early here: 5000 gave the best no-transfer reward in this project's screen."""
    alpha_decay: str = "boyan"
    """boyan: Boyan decay / ||phi(s)||_1; boyan_const: without the L1 division; const: alpha_0."""
    trace_cutoff: float = 1e-4
    """Trace entries that decay to this or below are dropped (RLPy keeps them): short traces."""

    max_rollback_share: float = 0.1
    """Diverged: once over 1000 updates, a run whose share of rolled-back updates (an update
    that made the weights non-finite) exceeds this is stopped and recorded as failed. Tuned
    runs roll back none; alpha0=1e30 rolls back 86 %."""

    def __post_init__(self) -> None:
        def fail(key: str, allowed: str) -> None:
            raise ValueError(f"algorithm.{key} must {allowed}, got {getattr(self, key)!r}")

        for f in fields(self):
            value = getattr(self, f.name)
            if f.type == "float" and (isinstance(value, bool) or not isinstance(value, (int, float))):
                fail(f.name, "be a number")
        if not 0.0 <= self.epsilon <= 1.0:
            fail("epsilon", "lie in [0, 1]")
        if not 0.0 <= self.lambda_ <= 1.0:
            fail("lambda_", "lie in [0, 1]")
        if not 0.0 <= self.gamma < 1.0:
            fail("gamma", "lie in [0, 1)")
        if not (math.isfinite(self.alpha0) and self.alpha0 > 0.0):
            fail("alpha0", "be a finite learning rate > 0")
        if not (math.isfinite(self.boyan_n0) and self.boyan_n0 >= 0.0):
            fail("boyan_n0", "be finite and >= 0")
        if self.alpha_decay not in LEARNING_RATE_DECAYS:
            fail("alpha_decay", "be one of " + ", ".join(LEARNING_RATE_DECAYS))
        if not 0.0 <= self.trace_cutoff < 1.0:
            fail("trace_cutoff", "lie in [0, 1)")
        if not 0.0 < self.max_rollback_share <= 1.0:
            fail("max_rollback_share", "lie in (0, 1]")

    def to_dict(self) -> dict:
        return asdict(self)


def boyan_rate(alpha0: float, n0: float, episode: int) -> float:
    """Boyan's schedule alpha_0 * (N0 + 1) / (N0 + (episode + 1) ** 1.1); episode counts from 0."""
    return alpha0 * (n0 + 1.0) / (n0 + (episode + 1.0) ** 1.1)


class Representation(Protocol):
    """What the learner needs of a feature map phi(s): sparse active features."""

    name: str
    num_features: int
    max_active: int

    def active_features(self, observation: np.ndarray, index_out: np.ndarray, value_out: np.ndarray) -> int:
        """Write phi(s)'s nonzero entries to the buffers, indices strictly ascending; return
        their count."""


class LinearQLearner:
    """Implements the ``Learner`` protocol (learners/base.py) for linear Q(lambda).

    ``act(obs, explore=True)`` is epsilon-greedy with the learner's own generator (seeded),
    ties among the greedy actions broken uniformly at random. ``act(obs, explore=False)`` is
    the greedy policy for evaluation: it breaks ties by the lowest action index and touches
    neither the generator nor any learning state.

    An episode ends either with a terminal transition (``observe(..., terminated=True)``) or
    with ``end_episode()`` (truncation); both clear the traces and advance the Boyan episode
    counter, once per episode, so calling ``end_episode`` after a terminal transition is safe.
    """

    representations = ("rbf", "fsr")
    """The representation options it learns on (conf: representation=...)."""

    @classmethod
    def from_params(cls, *, representation: Representation, num_actions: int, seed: int, world=None,
                    **params) -> "LinearQLearner":
        """``algorithm=linear_q``'s ``_target_``: the learner of the group's keys."""
        return cls(config_from_mapping(LinearQConfig, params, "algorithm"), representation, num_actions, seed)

    def __init__(self, config: LinearQConfig, representation: Representation, num_actions: int = 11, seed: int = 0):
        if isinstance(num_actions, bool) or not isinstance(num_actions, (int, np.integer)) or num_actions < 1:
            raise ValueError(f"num_actions must be an integer >= 1, got {num_actions!r}")
        self.config = config
        self.representation = representation
        self.num_actions = int(num_actions)
        self.seed = seed
        self._rng = np.random.default_rng(seed)
        self._num_features = representation.num_features
        # Weights stored feature-major (entry i * num_actions + a is theta_a[i]), so Q(s, .) for
        # all actions reads one short contiguous row per active feature; ``theta`` is the
        # (num_actions, num_features) view of the copy-paste blocks.
        self._theta = np.zeros(self._num_features * self.num_actions)
        self._trace_decay = config.gamma * config.lambda_
        self._divide_by_l1 = config.alpha_decay == "boyan"
        # Feature buffers: s (the state being acted in) and s' (the next state), swapped after
        # each non-terminal step so the next act() finds phi(s') already computed. The key (the
        # observation's bytes) says which observation the s buffers hold.
        size = representation.max_active
        self._s_index, self._s_value = np.empty(size, dtype=np.int64), np.empty(size)
        self._n_index, self._n_value = np.empty(size, dtype=np.int64), np.empty(size)
        self._s_count, self._s_key = 0, b""
        # Row 0: Q(s', .) before an update (the TD target); row 1: Q(s, .) of the state in the
        # s buffers under the current theta, which observe() leaves for the act() that follows.
        self._q = np.empty((2, self.num_actions))
        self._q_key, self._q_best, self._q_ties = b"", 0, 0
        # Separate buffers for greedy (evaluation) calls, which must leave the learner untouched.
        self._eval_index, self._eval_value = np.empty(size, dtype=np.int64), np.empty(size)
        self._eval_q = np.empty(self.num_actions)
        # Sparse trace, sorted by weight index: row ``_trace_row`` of (index, value) holds the
        # current entries, a step writes the merged trace into the other row (grown on demand).
        capacity = 1024
        self._trace_index = np.empty((2, capacity), dtype=np.int64)
        self._trace_value = np.empty((2, capacity))
        self._trace_backup = np.empty(capacity)  # theta before an update, for a rollback
        self._trace_row, self._trace_count = 0, 0
        self._episode = 0
        self._episode_open = False
        self._updates = 0
        self._rollbacks = 0
        self._warned = False
        self._rate = self._schedule()

    # --- the Learner protocol ---------------------------------------------------------------

    def act(self, observation: np.ndarray, explore: bool = True) -> int:
        obs = np.asarray(observation, dtype=np.float64)
        if not explore:
            n = self.representation.active_features(obs, self._eval_index, self._eval_value)
            best, _ = _q_values(self._theta, self._eval_index, self._eval_value, n, self._eval_q)
            return best  # ties: lowest index, no randomness
        rng = self._rng
        if rng.random() < self.config.epsilon:
            return int(rng.integers(self.num_actions))
        key = obs.tobytes()
        if key != self._q_key:
            n = self._s_count if key == self._s_key else self._state_features(obs, key)
            self._q_best, self._q_ties = _q_values(self._theta, self._s_index, self._s_value, n, self._q[1])
            self._q_key = key
        if self._q_ties == 1:
            return self._q_best
        q = self._q[1]
        return int(np.flatnonzero(q == q[self._q_best])[rng.integers(self._q_ties)])

    def observe(self, observation: np.ndarray, action: int, reward: float,
                next_observation: np.ndarray, terminated: bool) -> None:
        if not 0 <= action < self.num_actions:
            raise ValueError(f"action must lie in [0, {self.num_actions}), got {action!r}")
        obs = np.asarray(observation, dtype=np.float64)
        key = obs.tobytes()
        s_count = self._s_count if key == self._s_key else self._state_features(obs, key)
        if terminated:
            n_count = 0  # phi(terminal) = 0: no bootstrap
        else:
            nxt = np.asarray(next_observation, dtype=np.float64)
            n_count = self.representation.active_features(nxt, self._n_index, self._n_value)
        if self._trace_count + s_count > self._trace_index.shape[1]:
            self._grow_trace(self._trace_count + s_count)
        self._trace_count, status, best, ties = _learn(
            self._theta, int(action), float(reward), self.config.gamma, bool(terminated),
            self._s_index, self._s_value, s_count, self._n_index, self._n_value, n_count,
            self._trace_index, self._trace_value, self._trace_row, self._trace_count,
            self._trace_decay, self.config.trace_cutoff, self._rate, self._divide_by_l1,
            self._trace_backup, self._q,
        )
        self._trace_row ^= 1
        self._episode_open = True
        if status == _UPDATED:
            self._updates += 1
        elif status == _ROLLED_BACK:
            self._rollbacks += 1
            if not self._warned:
                self._warned = True
                warnings.warn(
                    "linear Q(lambda): an update made the weights non-finite and was rolled back "
                    "(further rollbacks are counted in stats['rollbacks'] without warning)",
                    RuntimeWarning, stacklevel=2,
                )
        if terminated:
            self._q_key = b""
            self._close_episode()
        else:
            # s' becomes the next s: its features and its Q values under the new theta are ready.
            self._s_index, self._n_index = self._n_index, self._s_index
            self._s_value, self._n_value = self._n_value, self._s_value
            self._s_count, self._s_key = n_count, nxt.tobytes()
            self._q_key, self._q_best, self._q_ties = self._s_key, best, ties

    def end_episode(self) -> None:
        if self._episode_open:
            self._close_episode()

    def state_dict(self) -> dict[str, Any]:
        """Plain arrays (``np.savez`` them; no pickle). The trace is (flat weight index
        i * num_actions + a, value), sorted by index."""
        row, n = self._trace_row, self._trace_count
        return {
            "theta": self._theta.reshape(self._num_features, self.num_actions).T.copy(),
            "episode": np.int64(self._episode),
            "episode_open": np.bool_(self._episode_open),
            "updates": np.int64(self._updates),
            "rollbacks": np.int64(self._rollbacks),
            "trace_index": self._trace_index[row, :n].copy(),
            "trace_value": self._trace_value[row, :n].copy(),
            "rng_state": np.array(rng_state_words(self._rng), dtype=np.uint64),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        theta = np.asarray(state["theta"], dtype=np.float64)
        if theta.shape != self.theta.shape:
            raise ValueError(
                f"checkpoint theta has shape {theta.shape}, this learner {self.theta.shape} "
                "(different representation or number of actions)"
            )
        trace_index = np.asarray(state["trace_index"], dtype=np.int64)
        trace_value = np.asarray(state["trace_value"], dtype=np.float64)
        if (trace_index.ndim != 1 or trace_index.shape != trace_value.shape
                or np.any(np.diff(trace_index) <= 0)
                or (len(trace_index) and not 0 <= trace_index[0] <= trace_index[-1] < theta.size)):
            raise ValueError("checkpoint trace_index/trace_value must be matching 1-D arrays of "
                             "ascending weight indices")
        self.theta[:] = theta
        self._episode = int(state["episode"])
        self._episode_open = bool(state["episode_open"])
        self._updates = int(state["updates"])
        self._rollbacks = int(state["rollbacks"])
        restore_rng_state(self._rng, state["rng_state"])
        n = len(trace_index)
        self._trace_count = 0
        if n > self._trace_index.shape[1]:
            self._grow_trace(n)
        self._trace_index[self._trace_row, :n] = trace_index
        self._trace_value[self._trace_row, :n] = trace_value
        self._trace_count = n
        self._rate = self._schedule()
        self._s_key = self._q_key = b""

    @property
    def stats(self) -> dict[str, float]:
        return {
            "updates": float(self._updates),
            "rollbacks": float(self._rollbacks),
            "episodes": float(self._episode),
            "learning_rate": self._rate,
        }

    def divergence(self) -> str | None:
        """Why the learner has diverged beyond what rollbacks absorb; None while it has not."""
        attempts = self._updates + self._rollbacks
        if attempts >= _DIVERGENCE_MIN_UPDATES and self._rollbacks > self.config.max_rollback_share * attempts:
            return (f"{self._rollbacks} of {attempts} updates rolled back (non-finite weights), "
                    f"above algorithm.max_rollback_share={self.config.max_rollback_share:g}")
        return None

    # --- inspection ---------------------------------------------------------------------------

    @property
    def theta(self) -> np.ndarray:
        """Weights as a writable (num_actions, num_features) view: row a is theta_a."""
        self._q_key = b""  # the caller may write to it: drop the Q values kept for act()
        return self._theta.reshape(self._num_features, self.num_actions).T

    @property
    def learning_rate(self) -> float:
        """The schedule's alpha for the current episode, before the division by ||phi(s)||_1."""
        return self._rate

    def q_values(self, observation) -> np.ndarray:
        """Q(s, .) for all actions (a fresh array; the learner is not changed)."""
        obs = np.asarray(observation, dtype=np.float64)
        n = self.representation.active_features(obs, self._eval_index, self._eval_value)
        q = np.empty(self.num_actions)
        _q_values(self._theta, self._eval_index, self._eval_value, n, q)
        return q

    def td_error(self, observation, action: int, reward: float, next_observation, terminated: bool) -> float:
        """delta of a transition under the current weights (before ``observe`` learns from it);
        a signal for curricula (transfer/strategy.py), the learner is not changed."""
        bootstrap = 0.0 if terminated else float(np.max(self.q_values(next_observation)))
        return reward + self.config.gamma * bootstrap - float(self.q_values(observation)[action])

    def trace(self) -> np.ndarray:
        """The eligibility trace as a dense (num_actions, num_features) array."""
        e = np.zeros(self._theta.size)
        row, n = self._trace_row, self._trace_count
        e[self._trace_index[row, :n]] = self._trace_value[row, :n]
        return e.reshape(self._num_features, self.num_actions).T.copy()

    # --- internals ----------------------------------------------------------------------------

    def _schedule(self) -> float:
        c = self.config
        if c.alpha_decay == "const":
            return c.alpha0
        return boyan_rate(c.alpha0, c.boyan_n0, self._episode)

    def _state_features(self, obs: np.ndarray, key: bytes) -> int:
        """phi(s) into the s buffers, marked by ``key``."""
        self._s_count = self.representation.active_features(obs, self._s_index, self._s_value)
        self._s_key = key
        return self._s_count

    def _close_episode(self) -> None:
        self._trace_count = 0
        self._episode += 1
        self._episode_open = False
        self._rate = self._schedule()

    def _grow_trace(self, needed: int) -> None:
        size = max(needed, 2 * self._trace_index.shape[1])
        index, value = np.empty((2, size), dtype=np.int64), np.empty((2, size))
        row, n = self._trace_row, self._trace_count
        index[row, :n], value[row, :n] = self._trace_index[row, :n], self._trace_value[row, :n]
        self._trace_index, self._trace_value = index, value
        self._trace_backup = np.empty(size)


# What one learning step did (returned by _learn).
_UPDATED, _ROLLED_BACK, _SKIPPED = 0, 1, 2


@njit(cache=True)
def _q_values(theta, index, value, count, out):
    """out[a] = theta_a . phi(s) over the active features; returns (first argmax, tie count)."""
    num_actions = out.shape[0]
    out[:] = 0.0
    for j in range(count):
        row = index[j] * num_actions
        v = value[j]
        for a in range(num_actions):
            out[a] += theta[row + a] * v
    best = 0
    ties = 1
    for a in range(1, num_actions):
        if out[a] > out[best]:
            best = a
            ties = 1
        elif out[a] == out[best]:
            ties += 1
    return best, ties


@njit(cache=True)
def _learn(theta, action, reward, gamma, terminated, s_index, s_value, s_count,
           n_index, n_value, n_count, trace_index, trace_value, row, trace_count,
           trace_decay, trace_cutoff, rate, divide_by_l1, backup, q):
    """One Q(lambda) step. The trace is read from ``row`` and written, merged, to ``1 - row``.

    Returns (new trace count, status, greedy action at s', its tie count); ``q[1]`` receives
    Q(s', .) under the updated weights (what the next act() needs).
    """
    num_actions = q.shape[1]
    # TD error with the weights before the update.
    q_sa = 0.0
    l1 = 0.0
    for j in range(s_count):
        q_sa += theta[s_index[j] * num_actions + action] * s_value[j]
        l1 += abs(s_value[j])
    target = reward
    if not terminated:
        best, _ = _q_values(theta, n_index, n_value, n_count, q[0])
        target += gamma * q[0, best]
    step = (rate / l1 if divide_by_l1 else rate) * (target - q_sa)
    apply = l1 > 0.0 and np.isfinite(step)  # RLPy skips the update without active features

    # One pass in index order: e <- min(gamma * lambda * e + phi(s, a), 1), old entries that
    # decayed to the cutoff dropped, and theta <- theta + alpha * delta * e on what remains.
    old_index, old_value = trace_index[row], trace_value[row]
    new_index, new_value = trace_index[1 - row], trace_value[1 - row]
    end = np.iinfo(np.int64).max
    i = j = m = 0
    finite = True
    while i < trace_count or j < s_count:
        f_old = old_index[i] if i < trace_count else end
        f_new = s_index[j] * num_actions + action if j < s_count else end
        if f_old < f_new:
            f, e = f_old, old_value[i] * trace_decay
            i += 1
            if e <= trace_cutoff:
                continue
        elif f_new < f_old:
            f, e = f_new, min(s_value[j], 1.0)
            j += 1
        else:
            f, e = f_old, min(old_value[i] * trace_decay + s_value[j], 1.0)
            i += 1
            j += 1
        new_index[m] = f
        new_value[m] = e
        if apply:
            backup[m] = theta[f]
            theta[f] += step * e
            finite &= np.isfinite(theta[f])
        m += 1

    # All or nothing: a non-finite weight rolls the whole update back.
    status = _UPDATED
    if not apply:
        status = _SKIPPED if l1 == 0.0 else _ROLLED_BACK
    elif not finite:
        for k in range(m):
            theta[new_index[k]] = backup[k]
        status = _ROLLED_BACK
    best, ties = _q_values(theta, n_index, n_value, n_count, q[1])
    return m, status, best, ties
