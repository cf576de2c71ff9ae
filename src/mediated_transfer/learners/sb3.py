"""Stable-Baselines3's PPO and DQN as learners of this project (``algorithm=sb3_ppo``, ``sb3_dqn``).

SB3 learns in its own loop (``model.learn``), not transition by transition, so these learners do
not take ``observe``: run_sb3.py drives them on ``TransferWrapper`` (the same strategies as the
project's loop) and evaluates them at the same points, with the same greedy evaluation. What they
share with the other learners: ``act(obs, explore=False)`` (the deterministic policy: SB3's
``predict(deterministic=True)``), ``divergence``, ``stats`` and ``state_dict`` (the policy's
tensors, for the saved learner).

Representation (what the policy and value networks see):

- ``network``: the sensor vector of eq. (2) as it is; SB3's MlpPolicy learns its own features.
- ``rbf`` / ``fsr``: the representation's features of the sensor vector (learners/rbf.py,
  fsr.py), computed by a fixed features extractor in front of the MLP. Rollout and replay
  buffers keep the 11-dim sensor vector. With ``algorithm.net_arch=[]`` the networks are
  linear in the features, as linear Q(lambda) is.

Hyperparameters are PROVISIONAL: Stable-Baselines3 2.x's defaults (those of ``PPO`` / ``DQN`` and
their MlpPolicy), which rl-zoo3 also starts from; no study has tuned them for this world.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from ..env.task import OBSERVATION_SIZE, PICKING_LOCATIONS
from ..mapping import config_from_mapping

NUM_ACTIONS = len(PICKING_LOCATIONS) + 6  # 5 picks, 4 moves, 2 rotations

ACTIVATIONS = ("tanh", "relu")
MAX_TORCH_THREADS = 1024
"""torch refuses absurd thread counts only when the learner is built; refuse them up front."""
MAX_ENVS = 256
"""Most PPO training environments in one run: each is a physics world in the run's process."""
MAX_WIDTH = 1 << 20
"""Widest hidden layer accepted: a wider one could not be allocated (checked before memory)."""


# --------------------------------------------------------------------------------------------
# Config
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SB3PPOConfig:
    """Hyperparameters of SB3's PPO (``algorithm=sb3_ppo``).

    PROVISIONAL: Stable-Baselines3 2.x's defaults (``PPO.__init__``, MlpPolicy), the starting
    point of rl-zoo3's tuned values; not tuned for this world.
    """

    learning_rate: float = 3e-4
    """Adam's constant step size (SB3 default)."""
    n_steps: int = 2048
    """Learning steps per rollout, after which the policy is updated (SB3 default)."""
    batch_size: int = 64
    """Minibatch size of the updates (SB3 default)."""
    n_epochs: int = 10
    """Passes over each rollout (SB3 default)."""
    gamma: float = 0.99
    """Discount factor, in [0, 1) (SB3 default)."""
    gae_lambda: float = 0.95
    """Generalised advantage estimation's lambda, in [0, 1] (SB3 default)."""
    clip_range: float = 0.2
    """Clipping of the policy's probability ratio (SB3 default)."""
    normalize_advantage: bool = True
    """Normalise the advantages per minibatch (SB3 default)."""
    ent_coef: float = 0.0
    """Weight of the entropy bonus (SB3 default: none)."""
    vf_coef: float = 0.5
    """Weight of the value loss (SB3 default)."""
    max_grad_norm: float = 0.5
    """Clip the gradient's global L2 norm to this (SB3 default)."""
    target_kl: float | None = None
    """Stop an update's epochs early beyond this KL divergence; None: never (SB3 default)."""
    net_arch: list[int] = field(default_factory=lambda: [64, 64])
    """Hidden layer widths of the policy network and, separately, of the value network (SB3's
    MlpPolicy default); [] makes both linear in their input."""
    activation: str = "tanh"
    """Activation of the hidden layers: tanh (SB3's default for PPO) or relu."""
    torch_threads: int = 1
    """torch intra-op threads (process-wide); 1 because runs are parallelised across processes."""
    n_envs: int = 1
    """Training environments stepped together (SB3's DummyVecEnv, one process), each episode's
    task chosen by the run's one strategy (run_sb3.py); a rollout is ``n_steps`` x ``n_envs``
    learning steps. Default 1: one episode at a time, as the paper's learners learn and as every
    PPO run committed so far computed (their results and fingerprints stay valid). More is
    faster (the policy acts for all environments in one forward pass); see run_sb3.py for what
    it changes."""

    def __post_init__(self) -> None:
        _check_common(self)
        _check_ints(self, ("n_steps", "n_epochs"), low=1)
        if isinstance(self.n_envs, bool) or not isinstance(self.n_envs, int) or not 1 <= self.n_envs <= MAX_ENVS:
            _fail(self, "n_envs", f"an integer in [1, {MAX_ENVS}]")
        # SB3 normalises advantages over a minibatch: one sample has no spread.
        _check_ints(self, ("batch_size",), low=2)
        if self.batch_size > self.n_steps * self.n_envs:
            rollout = (f"algorithm.n_steps ({self.n_steps})" if self.n_envs == 1 else
                       f"algorithm.n_steps x algorithm.n_envs ({self.n_steps} x {self.n_envs})")
            raise ValueError(f"algorithm.batch_size ({self.batch_size}) must be <= {rollout}: "
                             "a minibatch is drawn from one rollout")
        if not 0.0 <= self.gae_lambda <= 1.0:
            _fail(self, "gae_lambda", "in [0, 1]")
        for key in ("clip_range", "max_grad_norm"):
            if not (getattr(self, key) > 0 and math.isfinite(getattr(self, key))):
                _fail(self, key, "a finite number > 0")
        for key in ("ent_coef", "vf_coef"):
            if not (getattr(self, key) >= 0 and math.isfinite(getattr(self, key))):
                _fail(self, key, "a finite number >= 0")
        if self.target_kl is not None and not (self.target_kl > 0 and math.isfinite(self.target_kl)):
            _fail(self, "target_kl", "a finite number > 0 or None (no early stop)")
        if not isinstance(self.normalize_advantage, bool):
            _fail(self, "normalize_advantage", "true or false")


@dataclass(frozen=True)
class SB3DQNConfig:
    """Hyperparameters of SB3's DQN (``algorithm=sb3_dqn``).

    PROVISIONAL: Stable-Baselines3 2.x's defaults (``DQN.__init__``, MlpPolicy), the starting
    point of rl-zoo3's tuned values; not tuned for this world. SB3's exploration schedule is a
    fraction of the run's budget: epsilon falls over the first 10 % (50k of the paper's 500k
    steps, as the project's DQN).
    """

    learning_rate: float = 1e-4
    """Adam's constant step size (SB3 default)."""
    buffer_size: int = 1_000_000
    """Replay buffer capacity in transitions (SB3 default; more than a run's 500k steps)."""
    learning_starts: int = 100
    """Learning steps before the first update (SB3 default)."""
    batch_size: int = 32
    """Transitions per gradient update (SB3 default)."""
    tau: float = 1.0
    """Soft update coefficient of the target network, in (0, 1]; 1: a hard copy (SB3 default)."""
    gamma: float = 0.99
    """Discount factor, in [0, 1) (SB3 default)."""
    train_freq: int = 4
    """Update every this many learning steps (SB3 default)."""
    gradient_steps: int = 1
    """Gradient steps per update (SB3 default)."""
    target_update_interval: int = 10_000
    """Learning steps between target network updates (SB3 default)."""
    exploration_fraction: float = 0.1
    """Fraction of the budget over which epsilon falls linearly, in [0, 1] (SB3 default)."""
    exploration_initial_eps: float = 1.0
    """Epsilon at the first learning step (SB3 default)."""
    exploration_final_eps: float = 0.05
    """Epsilon after the fall (SB3 default)."""
    max_grad_norm: float = 10.0
    """Clip the gradient's global L2 norm to this (SB3 default)."""
    net_arch: list[int] = field(default_factory=lambda: [64, 64])
    """Hidden layer widths of the Q-network (SB3's MlpPolicy default); [] makes it linear in
    its input."""
    activation: str = "relu"
    """Activation of the hidden layers: relu (SB3's default for DQN) or tanh."""
    torch_threads: int = 1
    """torch intra-op threads (process-wide); 1 because runs are parallelised across processes."""

    def __post_init__(self) -> None:
        _check_common(self)
        _check_ints(self, ("buffer_size", "batch_size", "train_freq", "gradient_steps",
                           "target_update_interval"), low=1)
        _check_ints(self, ("learning_starts",), low=0)
        if self.buffer_size < self.batch_size:
            raise ValueError(f"algorithm.buffer_size ({self.buffer_size}) must be >= algorithm.batch_size "
                             f"({self.batch_size}): the replay buffer must hold at least one batch")
        if not 0.0 < self.tau <= 1.0:
            _fail(self, "tau", "in (0, 1]")
        for key in ("exploration_fraction", "exploration_initial_eps", "exploration_final_eps"):
            if not 0.0 <= getattr(self, key) <= 1.0:
                _fail(self, key, "in [0, 1]")
        if not (self.max_grad_norm > 0 and math.isfinite(self.max_grad_norm)):
            _fail(self, "max_grad_norm", "a finite number > 0")


CONFIGS = {"sb3_ppo": SB3PPOConfig, "sb3_dqn": SB3DQNConfig}
ALGORITHMS = tuple(CONFIGS)
REPRESENTATIONS = ("network", "rbf", "fsr")
"""What the networks see: the sensor vector itself, or a representation's features of it."""


def _fail(config, key: str, allowed: str) -> None:
    raise ValueError(f"algorithm.{key} must be {allowed}, got {getattr(config, key)!r}")


def _check_ints(config, keys, low: int) -> None:
    for key in keys:
        value = getattr(config, key)
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            _fail(config, key, f"an integer >= {low}")


def _check_common(config) -> None:
    for f in fields(config):  # values from Python are not typed by Hydra
        value = getattr(config, f.name)
        if f.type.startswith("float") and value is not None and (
                isinstance(value, bool) or not isinstance(value, (int, float))):
            _fail(config, f.name, "a number")
    if not (config.learning_rate > 0 and math.isfinite(config.learning_rate)):
        _fail(config, "learning_rate", "a finite number > 0")
    if not 0.0 <= config.gamma < 1.0:
        _fail(config, "gamma", "in [0, 1)")
    arch = config.net_arch
    if not isinstance(arch, (list, tuple)) or any(
            isinstance(w, bool) or not isinstance(w, int) or not 1 <= w <= MAX_WIDTH for w in arch):
        _fail(config, "net_arch", f"a list of layer widths, integers in [1, {MAX_WIDTH}]")
    if config.activation not in ACTIVATIONS:
        _fail(config, "activation", " or ".join(ACTIVATIONS))
    _check_ints(config, ("torch_threads",), low=1)
    if config.torch_threads > MAX_TORCH_THREADS:
        _fail(config, "torch_threads", f"at most {MAX_TORCH_THREADS}")


def memory_bytes(algorithm: str, config, num_inputs: int, observation_size: int = OBSERVATION_SIZE,
                 num_actions: int = NUM_ACTIONS) -> int:
    """Estimated bytes of the model's largest arrays, from the config alone (nothing allocated).

    ``num_inputs``: the networks' input width (the sensor vector, or the representation's
    features); ``observation_size``, ``num_actions``: the world's (the paper's: 11 and 11).
    """
    widths = [num_inputs, *config.net_arch, num_actions]
    params = sum((a + 1) * b for a, b in zip(widths[:-1], widths[1:]))
    if algorithm == "sb3_ppo":
        # A policy and a value network of about that size; float32 weights, gradient and
        # Adam's two moments of each. The rollout: float64 sensor vectors and a few floats.
        total = 2 * 4 * 4 * params + config.n_steps * config.n_envs * (8 * observation_size + 6 * 4)
    else:
        # The Q-network and its target copy, the gradient and Adam's two moments; SB3's replay
        # buffer: float64 sensor vectors (observation and next), an int64 action, a float32
        # reward, done and timeout per transition.
        total = 5 * 4 * params + config.buffer_size * (2 * 8 * observation_size + 8 + 3 * 4)
    # The features of a minibatch (observations and next observations).
    return total + 2 * 4 * config.batch_size * num_inputs


# --------------------------------------------------------------------------------------------
# The SB3 model
# --------------------------------------------------------------------------------------------
@functools.cache
def _features_extractor_class():
    """SB3 features extractor giving a representation's dense features of each sensor vector
    (a class made on first use, so that SB3 is imported only by runs that use it)."""
    import torch
    from stable_baselines3.common.torch_layers import BaseFeaturesExtractor

    class RepresentationFeatures(BaseFeaturesExtractor):
        """phi(s) of ``representation`` (rbf or fsr), dense; fixed, so nothing to learn here."""

        def __init__(self, observation_space, representation):
            super().__init__(observation_space, features_dim=representation.num_features)
            self.representation = representation
            self._index = np.empty(representation.max_active, dtype=np.int64)
            self._value = np.empty(representation.max_active)

        def forward(self, observations: torch.Tensor) -> torch.Tensor:
            rows = observations.detach().cpu().numpy().astype(np.float64)
            out = np.zeros((len(rows), self.features_dim), dtype=np.float32)
            for i, row in enumerate(rows):
                n = self.representation.active_features(row, self._index, self._value)
                out[i, self._index[:n]] = self._value[:n]
            return torch.from_numpy(out)

    return RepresentationFeatures


def build_model(algorithm: str, config, representation, env, seed: int):
    """The SB3 model of ``algorithm`` with ``config`` on ``env`` (a Gymnasium env or an SB3
    VecEnv), seeded with ``seed`` (python, numpy and torch generators, the env's first reset);
    ``representation``: None for the sensor vector itself, else an RBF/FSR representation."""
    import torch
    from stable_baselines3 import DQN, PPO

    torch.set_num_threads(config.torch_threads)
    policy_kwargs: dict[str, Any] = {
        "net_arch": list(config.net_arch),
        "activation_fn": {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}[config.activation],
    }
    if representation is not None:
        policy_kwargs["features_extractor_class"] = _features_extractor_class()
        policy_kwargs["features_extractor_kwargs"] = {"representation": representation}
    common = dict(policy_kwargs=policy_kwargs, seed=seed, device="cpu", verbose=0)
    c = config
    if algorithm == "sb3_ppo":
        return PPO("MlpPolicy", env, learning_rate=c.learning_rate, n_steps=c.n_steps,
                   batch_size=c.batch_size, n_epochs=c.n_epochs, gamma=c.gamma,
                   gae_lambda=c.gae_lambda, clip_range=c.clip_range,
                   normalize_advantage=c.normalize_advantage, ent_coef=c.ent_coef,
                   vf_coef=c.vf_coef, max_grad_norm=c.max_grad_norm, target_kl=c.target_kl, **common)
    if algorithm == "sb3_dqn":
        return DQN("MlpPolicy", env, learning_rate=c.learning_rate, buffer_size=c.buffer_size,
                   learning_starts=c.learning_starts, batch_size=c.batch_size, tau=c.tau,
                   gamma=c.gamma, train_freq=c.train_freq, gradient_steps=c.gradient_steps,
                   target_update_interval=c.target_update_interval,
                   exploration_fraction=c.exploration_fraction,
                   exploration_initial_eps=c.exploration_initial_eps,
                   exploration_final_eps=c.exploration_final_eps,
                   max_grad_norm=c.max_grad_norm, **common)
    raise ValueError(f"algorithm={algorithm!r} is not an SB3 learner; allowed: {', '.join(ALGORITHMS)}")


# --------------------------------------------------------------------------------------------
# Learner
# --------------------------------------------------------------------------------------------
class SB3Learner:
    """An SB3 model behind the parts of the ``Learner`` interface that do not learn.

    ``env``: the environment the model learns on (run_sb3.py passes the TransferWrapper in a
    DummyVecEnv); None builds a target-scenario environment, for the spaces only (a saved
    learner, a learner that only acts).
    """

    representations = REPRESENTATIONS
    run_loop = "mediated_transfer.run_sb3.execute_sb3_run"
    """SB3 learns in its own loop, not the project's (run.py)."""

    @classmethod
    def ppo(cls, *, representation=None, num_actions: int, seed: int, world=None, **params) -> "SB3Learner":
        """``algorithm=sb3_ppo``'s ``_target_`` (a learner that acts; run_sb3.py makes the one that learns)."""
        return cls.of("sb3_ppo", params, representation, world, seed, num_actions)

    @classmethod
    def dqn(cls, *, representation=None, num_actions: int, seed: int, world=None, **params) -> "SB3Learner":
        """``algorithm=sb3_dqn``'s ``_target_``."""
        return cls.of("sb3_dqn", params, representation, world, seed, num_actions)

    @classmethod
    def of(cls, algorithm: str, params, representation, world, seed: int, num_actions: int = NUM_ACTIONS,
           env=None) -> "SB3Learner":

        config = config_from_mapping(CONFIGS[algorithm], params, "algorithm")
        return cls(algorithm, config, representation, world, seed, env=env, num_actions=num_actions)

    def __init__(self, algorithm: str, config, representation=None, world=None, seed: int = 0,
                 env=None, num_actions: int = NUM_ACTIONS):
        self.algorithm, self.config, self.num_actions = algorithm, config, num_actions
        if env is None:  # a learner that only acts (a saved one): SB3 takes the spaces from an env
            if world is None:
                from ..env.paper import PaperWorld

                world = PaperWorld()
            env = world.make_env("target")
        self.model = build_model(algorithm, config, representation, env, seed)
        self.episodes = 0

    def act(self, observation: np.ndarray, explore: bool = True) -> int:
        """``explore=False``: the deterministic policy (SB3's ``predict(deterministic=True)``:
        the most probable action, or the greedy one for DQN); it draws nothing and changes
        nothing. ``explore=True``: SB3's exploring policy (its global generators)."""
        import torch

        if explore:
            action, _ = self.model.predict(observation, deterministic=False)
            return int(action)
        # predict() without its conversions and its switch to eval mode (no layer here differs
        # between the modes); the observation is cast to float32 as predict() does.
        with torch.no_grad():
            obs = torch.as_tensor(np.asarray(observation, dtype=np.float32).reshape(1, -1))
            return int(self.model.policy._predict(obs, deterministic=True)[0])

    def observe(self, observation, action, reward, next_observation, terminated) -> None:
        raise NotImplementedError(f"{self.algorithm} learns in SB3's own loop (model.learn on a "
                                  "TransferWrapper, run_sb3.py), not transition by transition")

    def end_episode(self) -> None:
        raise NotImplementedError(f"{self.algorithm} learns in SB3's own loop, not episode by episode")

    def divergence(self) -> str | None:
        """Why the model has diverged (a non-finite parameter, from which Adam cannot come
        back); None while it has not."""
        import torch

        for name, parameter in self.model.policy.named_parameters():
            if not bool(torch.isfinite(parameter).all()):
                return f"the policy's parameter {name} is not finite"
        return None

    @property
    def stats(self) -> dict[str, float]:
        model = self.model
        stats = {"learning_steps": float(model.num_timesteps), "updates": float(model._n_updates),
                 "episodes": float(self.episodes)}
        if self.algorithm == "sb3_dqn":
            stats["epsilon"] = float(model.exploration_rate)
        return stats

    def state_dict(self) -> dict[str, Any]:
        """The policy's tensors (its networks; DQN's target network too) and the step count:
        enough to act as the trained model did (loads with ``torch.load(weights_only=True)``).
        Optimizer, buffers and generators are left out: learning on from it is not supported."""
        policy = {k: v.detach().clone() for k, v in self.model.policy.state_dict().items()}
        return {"policy": policy, "num_timesteps": int(self.model.num_timesteps),
                "episodes": self.episodes}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        try:
            self.model.policy.load_state_dict(dict(state["policy"]))
        except RuntimeError as error:  # torch lists every mismatch, one per line
            raise ValueError("the saved policy does not fit this configuration (check "
                             f"algorithm.net_arch and representation): {str(error).splitlines()[0]}") from None
        self.model.num_timesteps = int(state["num_timesteps"])
        self.episodes = int(state["episodes"])
