"""K deep Q-learners whose networks are stacked: one batched greedy forward for the K actions,
one batched update (batched matrix products, one clip-and-Adam pass over the stacked
parameters), on any torch device (``lockstep.device=cuda``: all the runs of a cell on a GPU).

Each run keeps what is its own: its random stream (exploration and batch sampling, drawn in the
order ``DQNLearner`` draws them), its replay buffer (a slice of one stacked buffer), its
initial weights (those of ``DQNLearner(config, seed)``), its Adam moments and its counters. The
maths is ``DQNLearner``'s (``dqn.ReferenceUpdate``: Huber loss of the TD error, the gradient
clipped to a global L2 norm, Adam); batched products sum in another order, so a run's curve
agrees with its single run statistically, not bit for bit (tests: update by update within a
tolerance). On the CPU the per-seed fast kernels are faster and exact (``lockstep/group.py``).

Per run, a CPU ``DQNLearner`` (``view``) carries the counters and receives the weights at
evaluation points: evaluation, divergence checks, statistics and saved learners use it as they
use a single run's learner.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from ..env.sensors import PAPER_SENSORS, Sensors
from ..learners.dqn import DQNConfig, DQNLearner


class StackedNetworks:
    """The layers of K networks as views into one (K, P) tensor laid out as ``QNetwork.flat``."""

    def __init__(self, flat: torch.Tensor, shapes: list[tuple[int, int]]):
        self.flat, self.shapes = flat, shapes
        self.num_distances = shapes[0][1]  # the first layer's input: the world's distances
        self.layers = []
        start = 0
        for out, inp in shapes:
            w = flat[:, start:start + out * inp].view(-1, out, inp)
            start += out * inp
            self.layers.append((w, flat[:, start:start + out]))
            start += out

    def forward(self, observations: torch.Tensor, keep: list | None = None) -> torch.Tensor:
        """Q of (K, B, n) observations (the world's sensor vectors) -> (K, B, actions).
        ``keep`` receives each layer's input (for the backward pass)."""
        h = observations[..., :self.num_distances]
        *hidden, (head_w, head_b) = self.layers
        for w, b in hidden:
            if keep is not None:
                keep.append(h)
            h = torch.baddbmm(b.unsqueeze(1), h, w.transpose(1, 2)).relu_()
        head_input = torch.cat([h, observations[..., self.num_distances:]], dim=2)
        if keep is not None:
            keep.append(head_input)
        return torch.baddbmm(head_b.unsqueeze(1), head_input, head_w.transpose(1, 2))


class StackedDQN:
    """K runs' deep Q-learners trained together (the learner group of ``lockstep.device=cuda``)."""

    def __init__(self, config: DQNConfig, seeds: list[int], num_actions: int = 11,
                 device: str | torch.device = "cpu", sensors: Sensors = PAPER_SENSORS):
        self.config, self.device, self.num_actions = config, torch.device(device), num_actions
        # The views: each run's learner as a single run would build it (weights, stream).
        self.views = [DQNLearner(config, num_actions=num_actions, seed=seed, sensors=sensors) for seed in seeds]
        K, first = len(seeds), self.views[0]
        # The replay row's slots for the world's sensor vector (a single run's buffer's).
        layout = first.buffer
        self._obs, self._next, self._action = layout.OBSERVATION, layout.NEXT_OBSERVATION, layout.ACTION
        self._reward, self._bootstrap, width = layout.REWARD, layout.BOOTSTRAP, layout.WIDTH
        self.shapes = first.network.shapes
        stack = torch.stack([v.network.flat.detach() for v in self.views]).to(self.device)
        self.online = StackedNetworks(stack, self.shapes)
        self.target = StackedNetworks(stack.clone(), self.shapes)
        self.grad = torch.zeros_like(stack)
        self.grads = StackedNetworks(self.grad, self.shapes).layers
        self.adam_mean, self.adam_sq_mean = torch.zeros_like(stack), torch.zeros_like(stack)
        self.adam_steps = 0
        self.buffer = torch.zeros(K, config.buffer_size, width, device=self.device)
        self._staged = np.zeros((K, width), np.float32)  # this step's transitions
        self._index = np.zeros((K, config.batch_size), np.int64)
        self._runs = torch.arange(K, device=self.device)[:, None]
        self.size = self.position = self.steps = 0
        self.last_loss = torch.zeros(K, device=self.device)
        self.grad_norm = torch.zeros(K, device=self.device)
        self._updates_start = max(config.learning_starts, config.batch_size)
        self._due = False

    # --- acting -----------------------------------------------------------------------------
    def act(self, members: list[int], observations: list[np.ndarray], explore: bool) -> list[int]:
        """Each member's epsilon-greedy action (greedy with ``explore=False``), drawing from
        its own stream as ``DQNLearner.act`` does; one batched forward for the greedy ones."""
        actions: list[int | None] = []
        for k in members:
            view = self.views[k]
            if explore and view.rng.random() < view.epsilon:
                actions.append(int(view.rng.integers(self.num_actions)))
            else:
                actions.append(None)
        greedy = [i for i, a in enumerate(actions) if a is None]
        if greedy:
            obs = torch.as_tensor(np.stack([observations[i] for i in greedy]), dtype=torch.float32)
            rows = torch.as_tensor([members[i] for i in greedy], device=self.device)
            with torch.no_grad():
                q = self._q(rows, obs.to(self.device))
            best = q.argmax(dim=1).cpu().tolist()  # the first on ties, as DQNLearner
            for i, a in zip(greedy, best):
                actions[i] = int(a)
        return actions  # type: ignore[return-value]

    def _q(self, rows: torch.Tensor, observations: torch.Tensor) -> torch.Tensor:
        """Q(s, .) of one observation per listed run: (len(rows), n) -> (len(rows), actions)."""
        # Every run greedy (most steps past the epsilon decay): the networks as they are, uncopied.
        nets = self.online if len(rows) == len(self.views) else StackedNetworks(self.online.flat[rows], self.shapes)
        return nets.forward(observations[:, None, :])[:, 0]

    # --- learning ---------------------------------------------------------------------------
    def observe(self, k: int, observation, action: int, reward: float, next_observation,
                terminated: bool) -> None:
        """Stage run k's transition; its batch indices are drawn now, from its stream, as
        ``DQNLearner.observe`` draws them (``learn`` does the work for all runs at once)."""
        row = self._staged[k]
        row[self._obs] = observation
        row[self._action] = action
        row[self._reward] = reward
        row[self._next] = next_observation
        row[self._bootstrap] = 0.0 if terminated else 1.0
        view, cfg = self.views[k], self.config
        # The view's counters advance as a single run's learner's would (epsilon reads them).
        view.steps += 1
        view.buffer.size = min(view.buffer.size + 1, view.buffer.capacity)
        view.buffer.position = (view.buffer.position + 1) % view.buffer.capacity
        self._due = view.buffer.size >= self._updates_start and view.steps % cfg.train_frequency == 0
        if self._due:
            self._index[k] = view.rng.integers(0, view.buffer.size, cfg.batch_size)

    def learn(self) -> None:
        """The step's work for every run: store the staged transitions, one batched update if
        one is due, the target copy every tau steps. Every run steps once per call."""
        cfg = self.config
        self.buffer[:, self.position] = torch.from_numpy(self._staged).to(self.device)
        self.position = (self.position + 1) % cfg.buffer_size
        self.size = min(self.size + 1, cfg.buffer_size)
        self.steps += 1
        if self._due:
            index = torch.from_numpy(self._index).to(self.device)
            self.update(self.buffer[self._runs, index])
        if self.steps % cfg.target_update_interval == 0:
            self.target.flat.copy_(self.online.flat)
            for view in self.views:
                view.target_syncs += 1

    def update(self, rows: torch.Tensor) -> torch.Tensor:
        """One deep Q-learning update of every run on its batch (K, B, width); returns the K
        mean Huber losses (before the step)."""
        if self.device.type == "cpu":  # subnormal Adam moments cost the CPU ~10x (dqn_kernels)
            torch.set_flush_denormal(True)
        try:
            with torch.no_grad():
                return self._update(rows)
        finally:
            if self.device.type == "cpu":
                torch.set_flush_denormal(False)

    def _update(self, rows: torch.Tensor) -> torch.Tensor:
        cfg = self.config
        B = rows.shape[1]
        actions = rows[..., self._action].long()
        best_next = self.target.forward(rows[..., self._next]).amax(dim=2)
        y = rows[..., self._reward] + cfg.gamma * rows[..., self._bootstrap] * best_next
        inputs: list[torch.Tensor] = []
        q = self.online.forward(rows[..., self._obs], keep=inputs)
        td = q.gather(2, actions[..., None])[..., 0] - y
        d = cfg.huber_delta
        self.last_loss = torch.where(td.abs() <= d, 0.5 * td * td, d * (td.abs() - 0.5 * d)).mean(dim=1)
        # dLoss/dQ(s, a): the TD error clipped to [-delta, delta], for the taken action only.
        delta = torch.zeros_like(q).scatter_(2, actions[..., None], (td.clamp(-d, d) / B)[..., None])
        layers = self.online.layers
        for layer in reversed(range(len(layers))):
            w, _ = layers[layer]
            gw, gb = self.grads[layer]
            gw.copy_(torch.bmm(delta.transpose(1, 2), inputs[layer]))
            gb.copy_(delta.sum(dim=1))
            if layer > 0:  # back through the layer, then through its input's ReLU
                width = layers[layer - 1][0].shape[1]
                delta = torch.bmm(delta, w[:, :, :width]) * (inputs[layer][..., :width] > 0)
        self._adam()
        return self.last_loss

    def _adam(self) -> None:
        """Clip each run's gradient to its global L2 norm, then Adam (torch.optim.Adam's
        formula), over the stacked parameters at once."""
        cfg = self.config
        self.adam_steps += 1
        t = self.adam_steps
        norm = self.grad.square().sum(dim=1).sqrt()
        self.grad_norm = norm
        if cfg.max_grad_norm is not None:  # the guard as in torch's clip_grad_norm_
            scale = torch.clamp(cfg.max_grad_norm / (norm + 1e-6), max=1.0)
            self.grad.mul_(scale[:, None])
        b1, b2 = cfg.adam_beta1, cfg.adam_beta2
        self.adam_mean.mul_(b1).add_(self.grad, alpha=1 - b1)
        self.adam_sq_mean.mul_(b2).addcmul_(self.grad, self.grad, value=1 - b2)
        denominator = (self.adam_sq_mean / (1 - b2 ** t)).sqrt_().add_(cfg.adam_epsilon)
        self.online.flat.addcdiv_(self.adam_mean, denominator, value=-cfg.learning_rate / (1 - b1 ** t))

    def end_episode(self, k: int) -> None:
        self.views[k].end_episode()

    # --- each run's learner, for evaluation, checks, statistics and saving ----------------------
    def learner(self, k: int, with_buffer: bool = False) -> DQNLearner:
        """Run k's learner with the current weights (and, ``with_buffer``, its replay buffer)."""
        view = self.views[k]
        with torch.no_grad():
            view.network.flat.copy_(self.online.flat[k].cpu())
            view.target_network.flat.copy_(self.target.flat[k].cpu())
        view.update.load_optimizer_state(self.adam_mean[k].cpu(), self.adam_sq_mean[k].cpu(),
                                         self.adam_steps)
        view.update.grad_norm = float(self.grad_norm[k])
        view.last_loss = float(self.last_loss[k])
        if with_buffer:
            view.buffer.transitions[:self.size] = self.buffer[k, :self.size].cpu().numpy()
        return view
