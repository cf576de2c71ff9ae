"""The paper's deep Q-learner (Sec. V, Fig. 2; Mnih et al. 2015), in the order it runs: replay
buffer, the learning step, the learner (its config: dqn_config.py; its network: dqn_network.py).

The network sees the sensor vector of eq. (2) in two parts: the 6 distances pass through 3
fully connected ReLU layers of 256 units; the 5-dim one-hot of the active picking location,
already a compact feature, is concatenated to the last hidden layer; a linear layer maps that to
the 11 action values. A target network, copied every tau learning steps, gives the bootstrap
values; transitions go into a replay buffer of size E and learning starts once it holds E_start
of them; Adam with a constant learning rate minimises the Huber loss of the TD error; epsilon
decays linearly from 1 to 0.1.

The learning step and the greedy action are written here plainly (autograd,
``torch.optim.Adam``, ``clip_grad_norm_``): ``algorithm.kernels=reference``. The default,
``algorithm.kernels=fast``, runs the same functions as hand-written kernels
(``dqn_kernels.py``), tested equal to these.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np

from ..env.sensors import PAPER_SENSORS, Sensors
from ..env.task import OBSERVATION_SIZE
from ..mapping import config_from_mapping
from .dqn_config import (KERNELS, MAX_TORCH_THREADS, NUM_BINARY, DQNConfig, forward_flops, layer_shapes,
                         update_flops)
from .dqn_network import F, QNetwork, torch  # torch, or without the deep extra its stand-in
from .rng_state import restore_rng_state, rng_state_words

__all__ = ["KERNELS", "MAX_TORCH_THREADS", "NUM_BINARY", "DQNConfig", "DQNLearner", "QNetwork", "ReplayBuffer",
           "forward_flops", "layer_shapes", "update_flops"]


# --------------------------------------------------------------------------------------------
# Replay buffer
# --------------------------------------------------------------------------------------------
class ReplayBuffer:
    """Ring buffer of the last E transitions, one float32 row each, so that sampling a batch is
    a single gather: [observation (n) | action | reward | next observation (n) | bootstrap],
    bootstrap being 1 unless the next state is terminal (then the TD target has no bootstrap
    term). n is the world's sensor vector's size (``observation_size``; the paper's: 11, the
    class attributes' layout)."""

    OBSERVATION = slice(0, OBSERVATION_SIZE)
    ACTION = OBSERVATION_SIZE
    REWARD = OBSERVATION_SIZE + 1
    NEXT_OBSERVATION = slice(OBSERVATION_SIZE + 2, 2 * OBSERVATION_SIZE + 2)
    BOOTSTRAP = 2 * OBSERVATION_SIZE + 2
    WIDTH = 2 * OBSERVATION_SIZE + 3

    @staticmethod
    def layout(observation_size: int) -> dict:
        """The row's slots for observations of ``observation_size`` entries."""
        n = observation_size
        return {"OBSERVATION": slice(0, n), "ACTION": n, "REWARD": n + 1,
                "NEXT_OBSERVATION": slice(n + 2, 2 * n + 2), "BOOTSTRAP": 2 * n + 2, "WIDTH": 2 * n + 3}

    def __init__(self, capacity: int, batch_size: int, observation_size: int = OBSERVATION_SIZE):
        if observation_size != OBSERVATION_SIZE:  # another world's sensor vector: its own slots
            self.__dict__.update(self.layout(observation_size))
        self.capacity, self.size, self.position = capacity, 0, 0
        self.transitions = np.zeros((capacity, self.WIDTH), np.float32)
        # One batch, reused by every sample; the torch views share its memory.
        self._batch = np.zeros((batch_size, self.WIDTH), np.float32)
        rows = torch.from_numpy(self._batch)
        self.batch = {
            "rows": self._batch,  # all of it, as numpy (the fast kernels unpack it themselves)
            "observations": rows[:, self.OBSERVATION],
            "actions": rows[:, self.ACTION],  # float32 (exact for action indices)
            "rewards": rows[:, self.REWARD],
            "next_observations": rows[:, self.NEXT_OBSERVATION],
            "bootstrap": rows[:, self.BOOTSTRAP],
        }

    def add(self, observation, action: int, reward: float, next_observation,
            terminated: bool) -> None:
        row = self.transitions[self.position]
        row[self.OBSERVATION] = observation
        row[self.ACTION] = action
        row[self.REWARD] = reward
        row[self.NEXT_OBSERVATION] = next_observation
        row[self.BOOTSTRAP] = 0.0 if terminated else 1.0
        self.position = (self.position + 1) % self.capacity
        self.size = min(self.size + 1, self.capacity)

    def sample(self, rng: np.random.Generator) -> dict:
        """A uniform batch (with replacement), written into the shared batch tensors."""
        index = rng.integers(0, self.size, len(self._batch))
        np.take(self.transitions, index, axis=0, out=self._batch)
        return self.batch


# --------------------------------------------------------------------------------------------
# The learning step: Huber loss of the TD error, autograd, clipping, Adam (the reference)
# --------------------------------------------------------------------------------------------
class ReferenceUpdate:
    """One gradient step of deep Q-learning on a replay batch, written with autograd:
    y = r + gamma * bootstrap * max_a' Q_target(s', a') (no gradient through the target),
    loss = mean Huber(Q(s, a) - y), the gradient clipped to global L2 norm ``max_grad_norm``,
    then ``torch.optim.Adam``. ``algorithm.kernels=reference`` learns with it; the fast kernels
    (``dqn_kernels.FastUpdate``) are tested equal to it."""

    def __init__(self, network: QNetwork, target: QNetwork, config: DQNConfig):
        self.config, self.network, self.target = config, network, target
        self.optimizer = torch.optim.Adam(
            [network.flat], lr=config.learning_rate, betas=(config.adam_beta1, config.adam_beta2),
            eps=config.adam_epsilon, foreach=False)
        self.grad_norm = 0.0  # of the last update's gradient, before clipping
        self.load_optimizer_state(torch.zeros_like(network.flat.detach()),
                                  torch.zeros_like(network.flat.detach()), 0)

    def __call__(self, batch: dict) -> float:
        """One update; returns the batch's mean Huber loss (before the step)."""
        cfg = self.config
        with torch.no_grad():
            best_next = self.target(batch["next_observations"]).max(dim=1).values
            y = batch["rewards"] + cfg.gamma * batch["bootstrap"] * best_next
        q = self.network(batch["observations"]).gather(1, batch["actions"].long()[:, None])
        loss = F.huber_loss(q.squeeze(1), y, delta=cfg.huber_delta)
        self.optimizer.zero_grad()
        loss.backward()
        max_norm = math.inf if cfg.max_grad_norm is None else cfg.max_grad_norm
        self.grad_norm = float(torch.nn.utils.clip_grad_norm_([self.network.flat], max_norm))
        self.optimizer.step()
        return loss.item()

    # Adam's state, named as in the checkpoints (shared with the fast kernels).
    @property
    def adam_mean(self) -> torch.Tensor:
        return self.optimizer.state[self.network.flat]["exp_avg"]

    @property
    def adam_sq_mean(self) -> torch.Tensor:
        return self.optimizer.state[self.network.flat]["exp_avg_sq"]

    @property
    def adam_steps(self) -> int:
        return int(self.optimizer.state[self.network.flat]["step"])

    def load_optimizer_state(self, mean: torch.Tensor, sq_mean: torch.Tensor, steps: int) -> None:
        self.optimizer.state[self.network.flat] = {
            "step": torch.tensor(float(steps)), "exp_avg": mean.clone(), "exp_avg_sq": sq_mean.clone()}


class ReferenceGreedyPolicy:
    """argmax_a Q(s, a) of one observation by the network's autograd-free torch forward."""

    def __init__(self, network: QNetwork):
        self.network = network

    def q_values(self, observation: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return self.network(torch.as_tensor(observation, dtype=torch.float32)[None])[0].numpy()

    def __call__(self, observation: np.ndarray) -> int:
        return int(np.argmax(self.q_values(observation)))  # the first on ties, as the kernel


# --------------------------------------------------------------------------------------------
# Learner
# --------------------------------------------------------------------------------------------
class DQNLearner:
    """Deep Q-learning with the paper's network, behind the ``Learner`` interface.

    A learning step is one ``observe`` call: the transition enters the replay buffer; once the
    buffer holds E_start transitions, every ``train_frequency``-th step does one gradient update;
    every tau-th step copies the online weights to the target network. Exploration is
    epsilon-greedy with epsilon linear in the learning step. All randomness after construction
    (exploration, batch sampling) comes from one numpy generator seeded with ``seed``; the
    initial weights come from a torch generator seeded with ``seed``.
    """

    representations = ("network",)
    """It learns its own features from the sensor vector."""

    @classmethod
    def from_params(cls, *, representation=None, num_actions: int, seed: int, world=None, **params) -> "DQNLearner":
        """``algorithm=dqn``'s ``_target_``: the learner of the group's keys, for the world's
        sensor layout (None: the paper's)."""
        sensors = getattr(world, "sensors", PAPER_SENSORS)
        return cls(config_from_mapping(DQNConfig, params, "algorithm"), num_actions, seed, sensors)

    def __init__(self, config: DQNConfig | None = None, num_actions: int = 11, seed: int = 0,
                 sensors: Sensors = PAPER_SENSORS):
        self.config = config = config if config is not None else DQNConfig()
        if isinstance(num_actions, bool) or not isinstance(num_actions, int) or num_actions < 1:
            raise ValueError(f"num_actions must be an integer >= 1, got {num_actions!r}")
        self.num_actions, self.sensors = num_actions, sensors
        torch.set_num_threads(config.torch_threads)
        self.rng = np.random.default_rng(seed)
        init = torch.Generator().manual_seed(seed)
        self.network = QNetwork(config.hidden_size, config.num_hidden_layers, num_actions, init, sensors)
        self.target_network = copy.deepcopy(self.network)
        self.buffer = ReplayBuffer(config.buffer_size, config.batch_size, sensors.size)
        if config.kernels == "fast":
            from .dqn_kernels import FastGreedyPolicy, FastUpdate  # numba compiles on import

            self.update = FastUpdate(self.network, self.target_network, config)
            self.greedy = FastGreedyPolicy(self.network)
        else:
            self.update = ReferenceUpdate(self.network, self.target_network, config)
            self.greedy = ReferenceGreedyPolicy(self.network)
        self._updates_start = max(config.learning_starts, config.batch_size)
        self.steps = self.target_syncs = self.episodes = 0
        self.last_loss = 0.0

    # --- exploration schedule -----------------------------------------------------------------
    @property
    def epsilon(self) -> float:
        cfg = self.config
        if cfg.epsilon_decay_steps == 0:
            return cfg.epsilon_end
        fraction = min(1.0, self.steps / cfg.epsilon_decay_steps)
        return cfg.epsilon_start + fraction * (cfg.epsilon_end - cfg.epsilon_start)

    # --- Learner interface ----------------------------------------------------------------------
    def act(self, observation: np.ndarray, explore: bool = True) -> int:
        if explore and self.rng.random() < self.epsilon:
            return int(self.rng.integers(self.num_actions))
        return self.greedy(observation)

    def observe(self, observation, action: int, reward: float, next_observation,
                terminated: bool) -> None:
        cfg = self.config
        self.buffer.add(observation, action, reward, next_observation, terminated)
        self.steps += 1
        if self.buffer.size >= self._updates_start and self.steps % cfg.train_frequency == 0:
            self.last_loss = self.update(self.buffer.sample(self.rng))
        if self.steps % cfg.target_update_interval == 0:
            self._sync_target()

    def end_episode(self) -> None:
        self.episodes += 1  # nothing else: DQN keeps no per-episode state

    def _sync_target(self) -> None:
        with torch.no_grad():
            self.target_network.flat.copy_(self.network.flat)
        self.target_syncs += 1

    def divergence(self) -> str | None:
        """Why the network has diverged (a non-finite loss, gradient or weight, from which Adam
        cannot come back); None while it has not."""
        if not math.isfinite(self.last_loss):
            return f"the TD loss is {self.last_loss}"
        if not math.isfinite(self.update.grad_norm):
            return f"the gradient norm is {self.update.grad_norm}"
        if not bool(torch.isfinite(self.network.flat).all()):
            return "the network's weights are not finite"
        return None

    def td_error(self, observation, action: int, reward: float, next_observation, terminated: bool) -> float:
        """delta of a transition under the online network (the target network's bootstrap is a
        detail of the update; a signal for curricula), the learner is not changed."""
        bootstrap = 0.0 if terminated else float(np.max(self.q_values(next_observation)))
        return reward + self.config.gamma * bootstrap - float(self.q_values(observation)[action])

    def q_values(self, observation: np.ndarray) -> np.ndarray:
        """Q(s, .) of the online network (a copy)."""
        return self.greedy.q_values(observation).copy()

    @property
    def stats(self) -> dict[str, float]:
        return {
            "learning_steps": float(self.steps),
            "updates": float(self.update.adam_steps),
            "target_syncs": float(self.target_syncs),
            "episodes": float(self.episodes),
            "epsilon": float(self.epsilon),
            "replay_size": float(self.buffer.size),
            "last_loss": float(self.last_loss),
            "last_grad_norm": float(self.update.grad_norm),
        }

    # --- checkpoints ----------------------------------------------------------------------------
    def state_dict(self) -> dict[str, Any]:
        """Tensors and ints only (loads with ``torch.load(..., weights_only=True)``)."""
        b = self.buffer
        state = {
            "network": self.network.flat.detach().clone(),
            "target_network": self.target_network.flat.detach().clone(),
            "adam_mean": self.update.adam_mean.clone(),
            "adam_sq_mean": self.update.adam_sq_mean.clone(),
            "adam_steps": self.update.adam_steps,
            "rng": torch.tensor(rng_state_words(self.rng), dtype=torch.int64),
            "steps": self.steps, "last_loss": self.last_loss, "grad_norm": self.update.grad_norm,
            "target_syncs": self.target_syncs, "episodes": self.episodes,
            "buffer_capacity": b.capacity, "buffer_size": b.size, "buffer_position": b.position,
        }
        state["buffer_transitions"] = torch.from_numpy(b.transitions[: b.size].copy())
        return state

    def load_state_dict(self, state: dict[str, Any]) -> None:
        expected = self.network.flat.shape
        for key in ("network", "target_network", "adam_mean", "adam_sq_mean"):
            if tuple(state[key].shape) != tuple(expected):
                raise ValueError(
                    f"checkpoint {key!r} has shape {tuple(state[key].shape)}, this learner's "
                    f"network needs {tuple(expected)} (check algorithm.hidden_size, "
                    f"algorithm.num_hidden_layers and num_actions)"
                )
        if int(state["buffer_capacity"]) != self.buffer.capacity:
            raise ValueError(
                f"checkpoint replay buffer has capacity {int(state['buffer_capacity'])}, "
                f"algorithm.buffer_size is {self.buffer.capacity}"
            )
        size = int(state["buffer_size"])
        # In-place copies: the numpy views used by acting and Adam stay valid.
        with torch.no_grad():
            self.network.flat.copy_(state["network"])
            self.target_network.flat.copy_(state["target_network"])
        self.update.load_optimizer_state(state["adam_mean"], state["adam_sq_mean"],
                                         int(state["adam_steps"]))
        restore_rng_state(self.rng, state["rng"])
        self.steps = int(state["steps"])
        self.last_loss, self.update.grad_norm = float(state["last_loss"]), float(state["grad_norm"])
        self.target_syncs, self.episodes = int(state["target_syncs"]), int(state["episodes"])
        self.buffer.transitions[:size] = state["buffer_transitions"].numpy()
        self.buffer.size, self.buffer.position = size, int(state["buffer_position"])
