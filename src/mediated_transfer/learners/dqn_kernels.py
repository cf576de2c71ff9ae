"""Fast kernels of the deep Q-learner (``algorithm.kernels=fast``, the default): the same update
and greedy action as the reference in ``dqn.py``, for speed.

Speed (660 runs of 500k learning steps on two cores) shapes this module, not the maths:
- for a 4-layer MLP on a batch of 32, autograd's and the optimiser's bookkeeping cost more than
  the matrix products themselves, so forward and backward are written out on preallocated
  buffers: torch matrix products for the 256-wide layers, small numba kernels for the rest;
- only the taken action's Q-value enters the loss, so the online head is evaluated (and
  differentiated) for that action alone, inside the same kernel as the TD target and the loss;
- the target network's weights are kept transposed (in, out), the layout in which a batch-32
  product runs fastest; the copy is refreshed whenever the target network changes;
- Adam and gradient clipping are one fused pass over the flat parameter vector;
- acting reads the live weights through numpy views (no copy, always current) in a compiled
  loop: ~10 us where a torch forward of one observation costs ~50-100 us.
The tests check these against the reference (autograd, ``torch.optim.Adam``,
``clip_grad_norm_``) step by step.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numba
import numpy as np
import torch


if TYPE_CHECKING:
    from .dqn_config import DQNConfig
    from .dqn_network import QNetwork


# --------------------------------------------------------------------------------------------
# The update: batch -> TD target and loss -> backward pass -> clipped Adam step
# --------------------------------------------------------------------------------------------
@numba.njit(fastmath=True, error_model="numpy", cache=True)
def _unpack(rows, distances, binary, next_distances, next_binary, observation_size):
    """Split replay rows [obs | action | reward | next obs | bootstrap] into contiguous arrays
    for the matrix products (the distances) and the head kernel (the one-hot part)."""
    nd = distances.shape[1]
    for i in range(rows.shape[0]):
        for j in range(nd):
            distances[i, j] = rows[i, j]
            next_distances[i, j] = rows[i, observation_size + 2 + j]
        for k in range(binary.shape[1]):
            binary[i, k] = rows[i, nd + k]
            next_binary[i, k] = rows[i, observation_size + 2 + nd + k]


@numba.njit(fastmath=True, error_model="numpy", cache=True)
def _loss_backward(q, target_q, head_input, head_w, actions, rewards, bootstrap, gamma, huber_delta,
                   delta_h, head_gw, head_gb, last_gb):
    """The TD loss and the backward pass through the head, for one batch.

    y = r + gamma * bootstrap * max_a' Q_target(s', a'); the loss is the mean Huber loss of
    Q(s, a) - y, whose derivative is the TD error clipped to [-delta, delta]. Only Q(s, a) of
    the taken action enters, so only that row of the head receives gradient. ``head_input`` is
    [h, one-hot], h the last hidden layer (all arrays C-contiguous, so the loops vectorise).
    Writes the head's weight and bias gradients, dLoss/dh passed back through h's ReLU
    (``delta_h``) and h's bias gradient; returns the loss."""
    batch, width = delta_h.shape
    num_actions, columns = q.shape[1], head_input.shape[1]
    head_gw[:] = 0.0
    head_gb[:] = 0.0
    last_gb[:] = 0.0
    loss = 0.0
    for i in range(batch):
        best = target_q[i, 0]
        for a in range(1, num_actions):
            best = max(best, target_q[i, a])
        a = int(actions[i])
        td = q[i, a] - (rewards[i] + gamma * bootstrap[i] * best)
        if abs(td) <= huber_delta:
            loss += 0.5 * td * td
        else:
            loss += huber_delta * (abs(td) - 0.5 * huber_delta)
        g = min(max(td, -huber_delta), huber_delta) / batch
        head_gb[a] += g
        for j in range(columns):
            head_gw[a, j] += g * head_input[i, j]
        for j in range(width):
            d = g * head_w[a, j] if head_input[i, j] > 0.0 else 0.0  # through the ReLU
            delta_h[i, j] = d
            last_gb[j] += d
    return loss / batch


@numba.njit(fastmath=True, error_model="numpy", cache=True)
def _relu_backward(delta, activation, bias_grad):
    """Pass ``delta`` back through a ReLU (zero where the unit was inactive, in place) and sum it
    over the batch into the layer's bias gradient."""
    batch, width = delta.shape
    bias_grad[:] = 0.0
    for i in range(batch):
        for j in range(width):
            if activation[i, j] <= 0.0:
                delta[i, j] = 0.0
            bias_grad[j] += delta[i, j]


@numba.njit(fastmath=True, error_model="numpy", cache=True)
def _adam_step(params, grad, mean, sq_mean, step_size, beta1, beta2, eps, bias2, max_norm):
    """One Adam step (torch.optim.Adam's formula) on flat vectors, after clipping ``grad`` to
    global L2 norm ``max_norm`` (<= 0: no clipping). ``step_size`` = lr / (1 - beta1^t),
    ``bias2`` = 1 / (1 - beta2^t). Returns the gradient norm before clipping."""
    total = np.float32(0.0)
    for i in range(grad.size):
        total += grad[i] * grad[i]
    norm = np.sqrt(np.float64(total))
    scale = np.float32(1.0)
    if max_norm > 0 and norm > max_norm:
        scale = np.float32(max_norm / (norm + 1e-6))  # the guard as in torch's clip_grad_norm_
    one = np.float32(1.0)
    for i in range(params.size):
        g = grad[i] * scale
        m = beta1 * mean[i] + (one - beta1) * g
        v = beta2 * sq_mean[i] + (one - beta2) * g * g
        mean[i] = m
        sq_mean[i] = v
        params[i] -= step_size * m / (np.sqrt(v * bias2) + eps)
    return norm


class FastUpdate:
    """One gradient step of deep Q-learning on a replay batch, on preallocated buffers: the
    reference ``dqn.ReferenceUpdate``'s function, with the same state (Adam's moments and step
    count, the last gradient norm)."""

    def __init__(self, network: QNetwork, target: QNetwork, config: DQNConfig):
        self.config = config
        B, H = config.batch_size, config.hidden_size
        num_binary = network.shapes[-1][1] - H
        self.online = network.layers(network.flat.detach())
        # The target network's weights, hidden layers transposed (in, out): a batch-32 product
        # runs fastest in that layout. The head stays (out, in), as the head kernel reads it.
        self._target_net, self._target_version = target, -1  # copied before first use
        self._transposed = [True] * config.num_hidden_layers + [False]
        self.target = [(torch.empty(w.t().shape if t else w.shape), torch.empty(b.shape))
                       for (w, b), t in zip(target.layers(target.flat.detach()), self._transposed)]
        self.grad_flat = torch.zeros_like(network.flat.detach())
        self.grads = network.layers(self.grad_flat)
        self.adam_mean = torch.zeros_like(self.grad_flat)
        self.adam_sq_mean = torch.zeros_like(self.grad_flat)
        self.adam_steps = 0
        self.grad_norm = 0.0  # of the last update's gradient, before clipping
        self._params_np = network.flat.detach().numpy()
        self._adam_np = (self.grad_flat.numpy(), self.adam_mean.numpy(), self.adam_sq_mean.numpy())
        layers, A = config.num_hidden_layers, network.shapes[-1][0]
        D = network.num_distances  # the world's distances (the paper's: 6)
        self.distances, self.next_distances = torch.zeros(B, D), torch.zeros(B, D)
        # The head's input [last hidden layer, one-hot]: the last hidden layer is written
        # straight into its slot, so the concatenation costs nothing.
        self.head_input, self.target_head_input = torch.zeros(B, H + num_binary), torch.zeros(B, H + num_binary)
        self.acts = [torch.zeros(B, H) for _ in range(layers - 1)] + [self.head_input[:, :H]]
        self.target_acts = [torch.zeros(B, H) for _ in range(layers - 1)] + [self.target_head_input[:, :H]]
        self.q, self.target_q = torch.zeros(B, A), torch.zeros(B, A)
        self.deltas = [torch.zeros(B, H) for _ in range(layers)]
        self._acts_np = [a.numpy() for a in self.acts]
        self._deltas_np = [d.numpy() for d in self.deltas]
        self._hidden_gb = [gb.numpy() for _, gb in self.grads[:-1]]
        self._unpacked = (self.distances.numpy(), self.head_input.numpy()[:, H:],
                          self.next_distances.numpy(), self.target_head_input.numpy()[:, H:])

    def load_optimizer_state(self, mean: torch.Tensor, sq_mean: torch.Tensor, steps: int) -> None:
        self.adam_mean.copy_(mean)  # in place: the numpy views stay valid
        self.adam_sq_mean.copy_(sq_mean)
        self.adam_steps = steps

    def _refresh_target(self) -> None:
        """Copy the target network's hidden layers transposed (and its head as is), if it changed
        since the last use (torch counts in-place writes to a tensor in its version)."""
        version = self._target_net.flat._version
        if version != self._target_version:
            for (w_copy, b_copy), (w, b), transpose in zip(
                    self.target, self._target_net.layers(self._target_net.flat.detach()),
                    self._transposed):
                w_copy.copy_(w.t() if transpose else w)
                b_copy.copy_(b)
            self._target_version = version

    def __call__(self, batch: dict) -> float:
        """One update; returns the batch's mean Huber loss (before the step)."""
        # Adam's moments of rarely-active weights decay into subnormal floats, which cost the
        # CPU ~10x per operation; flush them to zero during the update (this thread only, and
        # restored after, so nothing else in the process sees the switch).
        torch.set_flush_denormal(True)
        try:
            return self._update(batch)
        finally:
            torch.set_flush_denormal(False)

    def _update(self, batch: dict) -> float:
        cfg = self.config
        self._refresh_target()
        rows = batch["rows"]
        _unpack(rows, *self._unpacked, (rows.shape[1] - 3) // 2)

        # Forward: both networks (the target's hidden weights are stored transposed).
        h, th = self.distances, self.next_distances
        for (w, b), (wt, bt), out, tout in zip(self.online[:-1], self.target[:-1], self.acts,
                                               self.target_acts):
            h = torch.addmm(b, h, w.t(), out=out).relu_()
            th = torch.addmm(bt, th, wt, out=tout).relu_()
        (head_w, head_b), (target_head_w, target_head_b) = self.online[-1], self.target[-1]
        torch.addmm(head_b, self.head_input, head_w.t(), out=self.q)
        torch.addmm(target_head_b, self.target_head_input, target_head_w.t(), out=self.target_q)

        # TD target, loss and the backward pass through the head in one kernel.
        loss = _loss_backward(
            self.q.numpy(), self.target_q.numpy(), self.head_input.numpy(), head_w.numpy(), batch["actions"].numpy(), batch["rewards"].numpy(),
            batch["bootstrap"].numpy(), cfg.gamma, cfg.huber_delta, self._deltas_np[-1],
            *(g.numpy() for g in self.grads[-1]), self._hidden_gb[-1])

        # Backward through the hidden layers, last to first (dL/dW = delta^T h, dL/dh = delta W).
        inputs = [self.distances, *self.acts[:-1]]
        for layer in reversed(range(len(self.acts))):
            delta = self.deltas[layer]
            torch.mm(delta.t(), inputs[layer], out=self.grads[layer][0])
            if layer > 0:  # the distances need no gradient
                torch.mm(delta, self.online[layer][0], out=self.deltas[layer - 1])
                _relu_backward(self._deltas_np[layer - 1], self._acts_np[layer - 1],
                               self._hidden_gb[layer - 1])

        self.adam_steps += 1
        t = self.adam_steps
        self.grad_norm = _adam_step(
            self._params_np, *self._adam_np,
            np.float32(cfg.learning_rate / (1.0 - cfg.adam_beta1 ** t)),
            np.float32(cfg.adam_beta1), np.float32(cfg.adam_beta2), np.float32(cfg.adam_epsilon),
            np.float32(1.0 / (1.0 - cfg.adam_beta2 ** t)),
            0.0 if cfg.max_grad_norm is None else float(cfg.max_grad_norm),
        )
        return loss


# --------------------------------------------------------------------------------------------
# Acting: the greedy action from numpy views of the live online weights
# --------------------------------------------------------------------------------------------
@numba.njit(fastmath=True, error_model="numpy", cache=True)
def _q_values(flat, shapes, observation, hidden, q):
    """Q(s, .) of one observation into ``q``, reading the flat weight vector laid out as in
    ``QNetwork`` (``shapes``: (out, in) per layer); ``hidden``: (2, hidden_size) scratch.
    Returns argmax_a Q(s, a) (the first on ties)."""
    num_hidden = shapes.shape[0] - 1
    src, dst = hidden[0], hidden[1]
    for i in range(shapes[0, 1]):
        src[i] = observation[i]  # the distances
    start = 0
    for layer in range(num_hidden):
        rows, cols = shapes[layer, 0], shapes[layer, 1]
        w = flat[start:start + rows * cols].reshape((rows, cols))
        b = flat[start + rows * cols:start + rows * cols + rows]
        start += rows * cols + rows
        for r in range(rows):
            acc = b[r]
            for c in range(cols):
                acc += w[r, c] * src[c]
            dst[r] = max(acc, 0.0)
        src, dst = dst, src
    rows, cols = shapes[num_hidden, 0], shapes[num_hidden, 1]
    width = shapes[num_hidden - 1, 0]
    w = flat[start:start + rows * cols].reshape((rows, cols))
    b = flat[start + rows * cols:start + rows * cols + rows]
    best = 0
    for r in range(rows):
        acc = b[r]
        for c in range(width):
            acc += w[r, c] * src[c]
        for c in range(width, cols):  # the one-hot of the active picking location
            acc += w[r, c] * observation[shapes[0, 1] + c - width]
        q[r] = acc
        if acc > q[best]:
            best = r
    return best


class FastGreedyPolicy:
    """argmax_a Q(s, a) for one observation. Reads the online weights through a numpy view of
    the torch storage, so it always sees the latest update without copying; a compiled loop,
    because a torch (or numpy) forward of a single observation is mostly call overhead."""

    def __init__(self, network: QNetwork):
        self.flat = network.flat.detach().numpy()
        self.shapes = np.array(network.shapes, dtype=np.int64)
        # Scratch for the distances, then each hidden layer (a world may have more distances).
        self.hidden = np.zeros((2, max(network.shapes[0])), np.float32)
        self.q = np.zeros(network.shapes[-1][0], np.float32)

    def q_values(self, observation: np.ndarray) -> np.ndarray:
        _q_values(self.flat, self.shapes, observation, self.hidden, self.q)
        return self.q

    def __call__(self, observation: np.ndarray) -> int:
        return _q_values(self.flat, self.shapes, observation, self.hidden, self.q)
