"""Speed of the deep Q-learner: learning steps/s against Stable-Baselines3's DQN, side by side.

Both learn on their own ``MediatedInteractionEnv("target")`` with the same network (the paper's:
SB3 gets a features extractor that reproduces it exactly, see ``paper_features_extractor``),
batch size, train frequency, replay buffer, E_start, tau, Huber loss, gradient clipping and
Adam settings (``DQNConfig`` defaults), one torch thread each. A learning step is one
environment step with everything the learner does around it (act, store, update every
``train_frequency`` steps, target copy); each side uses its own loop (ours: the experiment
loop's act / observe / end_episode; SB3: ``model.learn``). Ours runs twice, with each
``algorithm.kernels``: ``fast`` (the default) and ``reference`` (autograd, torch.optim.Adam).
After a warm-up that fills E_start and ends the epsilon decay on every side (so the timed part
runs like the bulk of a long run: epsilon = 0.1, an update every ``train_frequency`` steps),
the sides alternate in short rounds; the reported ratios are medians of per-round ratios, so
load from other processes hits all sides alike. Aim: fast / SB3 >= 7.

Also reported: the achieved FLOP rate of our update (sample a batch, target forward, online
forward and backward, Adam) as a fraction of a plain torch matrix product's FLOP rate (square
512 x 512, float32, same thread count), measured in alternating rounds; aim >= 80 %. An
update's FLOPs are counted as 4 forward passes of the batch: the online forward, its backward
(~2x) and the target network's forward. Beside it, the ceiling: the same fraction for the
update's matrix products alone (the fast update's torch calls, same shapes and layouts, with
nothing between them): what is left between the two is everything else an update does.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import replace
from typing import Callable

import gymnasium
import torch

from ..env.task import NUM_DISTANCES
from ..learners.dqn import KERNELS, DQNConfig, DQNLearner, forward_flops, update_flops

WARMUP_STEPS = 2_000
ROUNDS = 5
MATMUL_SIZE = 512


def _make_target_env() -> gymnasium.Env:
    from ..env.mediated_env import MediatedInteractionEnv

    return MediatedInteractionEnv("target")


def paper_features_extractor():
    """SB3 features extractor computing the paper's network up to its head: the distances
    through the hidden ReLU layers, then the one-hot concatenated. With ``net_arch=[]`` SB3 adds
    the head, Linear(hidden + 5 -> 11): the whole network is exactly ``QNetwork``'s."""
    from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
    from torch import nn

    class PaperFeatures(BaseFeaturesExtractor):
        def __init__(self, observation_space, hidden_size: int = 256, num_hidden_layers: int = 3):
            binary = observation_space.shape[0] - NUM_DISTANCES
            super().__init__(observation_space, features_dim=hidden_size + binary)
            layers, width = [], NUM_DISTANCES
            for _ in range(num_hidden_layers):
                layers += [nn.Linear(width, hidden_size), nn.ReLU()]
                width = hidden_size
            self.hidden = nn.Sequential(*layers)

        def forward(self, observations: torch.Tensor) -> torch.Tensor:
            distances, picking = observations[:, :NUM_DISTANCES], observations[:, NUM_DISTANCES:]
            return torch.cat([self.hidden(distances), picking], dim=1)

    return PaperFeatures


def make_sb3_dqn(config: DQNConfig, env: gymnasium.Env, seed: int, warmup_steps: int = WARMUP_STEPS):
    """Stable-Baselines3 DQN with the same network and hyperparameters as ``config``; its
    epsilon decay ends within a first ``learn(warmup_steps)`` call, as ours does."""
    from stable_baselines3 import DQN

    if config.epsilon_decay_steps <= 0:
        raise ValueError("the SB3 comparison needs algorithm.epsilon_decay_steps > 0")
    if config.huber_delta != 1.0:  # SB3 hard-codes smooth_l1_loss, i.e. Huber with delta 1
        raise ValueError(f"the SB3 comparison needs algorithm.huber_delta == 1, got {config.huber_delta}")
    return DQN(
        "MlpPolicy", env, seed=seed, device="cpu", verbose=0,
        learning_rate=config.learning_rate, gamma=config.gamma,
        buffer_size=config.buffer_size, learning_starts=config.learning_starts,
        batch_size=config.batch_size, train_freq=(config.train_frequency, "step"),
        gradient_steps=1, target_update_interval=config.target_update_interval, tau=1.0,
        exploration_initial_eps=config.epsilon_start, exploration_final_eps=config.epsilon_end,
        # SB3's schedule runs over a fraction of each learn() call; the bench times only
        # steps after the warm-up call, whose fraction covers the decay.
        exploration_fraction=min(1.0, config.epsilon_decay_steps / warmup_steps),
        max_grad_norm=float("inf") if config.max_grad_norm is None else config.max_grad_norm,
        policy_kwargs=dict(
            features_extractor_class=paper_features_extractor(),
            features_extractor_kwargs=dict(hidden_size=config.hidden_size,
                                           num_hidden_layers=config.num_hidden_layers),
            net_arch=[],
            optimizer_kwargs=dict(betas=(config.adam_beta1, config.adam_beta2), eps=config.adam_epsilon),
        ),
    )


class _OurLoop:
    """The experiment loop around our learner: act, env step, observe, end_episode, reset."""

    def __init__(self, learner: DQNLearner, env: gymnasium.Env, seed: int):
        self.learner, self.env = learner, env
        self.observation, _ = env.reset(seed=seed)

    def advance(self, steps: int) -> float:
        learner, env, obs = self.learner, self.env, self.observation
        start = time.perf_counter()
        for _ in range(steps):
            action = learner.act(obs)
            next_obs, reward, terminated, truncated, _ = env.step(action)
            learner.observe(obs, action, reward, next_obs, terminated)
            if terminated or truncated:
                learner.end_episode()
                next_obs, _ = env.reset()
            obs = next_obs
        elapsed = time.perf_counter() - start
        self.observation = obs
        return elapsed


def _timed(fn: Callable[[], object]) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def matmul_gflops(size: int = MATMUL_SIZE, repeats: int = 20) -> float:
    """FLOP rate (GFLOP/s) of a plain float32 torch matrix product at the current threads."""
    a, b, out = torch.randn(size, size), torch.randn(size, size), torch.empty(size, size)
    torch.mm(a, b, out=out)

    def work():
        for _ in range(repeats):
            torch.mm(a, b, out=out)

    return 2 * size**3 * repeats / _timed(work) / 1e9


def products_alone_s(config: DQNConfig, repeats: int = 50) -> float:
    """Seconds of the fast update's matrix products alone, per update (same shapes, layouts
    and torch calls as ``dqn_kernels.FastUpdate``, nothing in between)."""
    B, H, layers = config.batch_size, config.hidden_size, config.num_hidden_layers
    head_in, A = H + NUM_DISTANCES - 1, 11  # [h, one-hot of 5]
    x, h = torch.randn(B, NUM_DISTANCES), torch.randn(B, H)
    w_first, w_first_t = torch.randn(H, NUM_DISTANCES), torch.randn(NUM_DISTANCES, H)
    w, w_t, b = torch.randn(H, H), torch.randn(H, H), torch.randn(H)
    head, head_x, head_b = torch.randn(A, head_in), torch.randn(B, head_in), torch.randn(A)
    out, q, g_first, g = torch.empty(B, H), torch.empty(B, A), torch.empty(H, NUM_DISTANCES), torch.empty(H, H)

    def update():
        for layer in range(layers):  # online forward, target forward (transposed weights)
            first = layer == 0
            torch.addmm(b, x if first else h, (w_first if first else w).t(), out=out).relu_()
            torch.addmm(b, x if first else h, w_first_t if first else w_t, out=out).relu_()
        torch.addmm(head_b, head_x, head.t(), out=q)
        torch.addmm(head_b, head_x, head.t(), out=q)
        for layer in reversed(range(layers)):  # backward: dW, then dX (not for the distances)
            torch.mm(h.t(), x if layer == 0 else h, out=g_first if layer == 0 else g)
            if layer > 0:
                torch.mm(h, w, out=out)

    update()
    return _timed(lambda: [update() for _ in range(repeats)]) / repeats


def run(steps: int = 5_000, *, config: DQNConfig | None = None,
        make_env: Callable[[], gymnasium.Env] = _make_target_env, seed: int = 0,
        rounds: int = ROUNDS, warmup_steps: int = WARMUP_STEPS, verbose: bool = True) -> dict:
    """Measure our DQN (fast and reference kernels) and SB3's DQN side by side for ``steps``
    timed learning steps each (after ``warmup_steps`` untimed ones), with ``config``
    (default: ``DQNConfig()``)."""
    if steps < rounds:
        raise ValueError(f"steps must be >= rounds ({rounds}), got {steps}")
    base = config if config is not None else DQNConfig()
    if base.learning_starts >= warmup_steps:
        raise ValueError(f"algorithm.learning_starts ({base.learning_starts}) must be below the "
                         f"bench warm-up ({warmup_steps} steps)")
    # The timed part should run at the final epsilon, like the bulk of a 500k-step run.
    config = DQNConfig(**{**base.to_dict(), "epsilon_decay_steps": warmup_steps // 2})
    torch.set_num_threads(config.torch_threads)

    ours = {kernels: _OurLoop(DQNLearner(replace(config, kernels=kernels), seed=seed), make_env(), seed)
            for kernels in KERNELS}
    sb3 = make_sb3_dqn(config, make_env(), seed, warmup_steps)
    ours_params = ours["fast"].learner.network.flat.numel()
    sb3_params = sum(p.numel() for p in sb3.q_net.parameters())
    if ours_params != sb3_params:
        raise RuntimeError(f"networks differ: ours {ours_params} parameters, SB3 {sb3_params}")

    for loop in ours.values():
        loop.advance(warmup_steps)
    sb3.learn(warmup_steps)
    torch.set_num_threads(config.torch_threads)  # in case SB3 changed it
    chunk = steps // rounds
    rates: dict[str, list[float]] = {name: [] for name in (*KERNELS, "sb3")}
    for _ in range(rounds):
        for kernels, loop in ours.items():
            rates[kernels].append(chunk / loop.advance(chunk))
        rates["sb3"].append(chunk / _timed(lambda: sb3.learn(chunk, reset_num_timesteps=False)))
    ratios = {k: statistics.median(o / s for o, s in zip(rates[k], rates["sb3"])) for k in KERNELS}

    # One update (sample included) against plain matmul and the update's products alone.
    n_updates = 50
    update_s: dict[str, list[float]] = {name: [] for name in (*KERNELS, "sb3")}
    matmul_rates, products_s = [], []
    for _ in range(rounds):
        for kernels, loop in ours.items():
            learner = loop.learner
            update_s[kernels].append(_timed(lambda: [learner.update(learner.buffer.sample(learner.rng))
                                                     for _ in range(n_updates)]) / n_updates)
        update_s["sb3"].append(_timed(lambda: sb3.train(n_updates, config.batch_size)) / n_updates)
        matmul_rates.append(matmul_gflops())
        products_s.append(products_alone_s(config))
    flops = update_flops(config)
    update_us = {k: statistics.median(v) * 1e6 for k, v in update_s.items()}
    matmul_rate = statistics.median(matmul_rates)
    update_gflops = flops / update_us["fast"] / 1e3
    products_gflops = flops / statistics.median(products_s) / 1e9

    result = {
        "timed_steps": chunk * rounds,
        "rounds": rounds,
        "torch_threads": config.torch_threads,
        "batch_size": config.batch_size,
        "train_frequency": config.train_frequency,
        "buffer_size": config.buffer_size,
        "network_parameters": ours_params,
        "ours_steps_per_s": statistics.median(rates["fast"]),
        "reference_steps_per_s": statistics.median(rates["reference"]),
        "sb3_steps_per_s": statistics.median(rates["sb3"]),
        "ratio": ratios["fast"],
        "reference_ratio": ratios["reference"],
        "ours_update_us": update_us["fast"],
        "reference_update_us": update_us["reference"],
        "sb3_update_us": update_us["sb3"],
        "update_mflop": flops / 1e6,
        "update_gflops": update_gflops,
        "matmul_gflops": matmul_rate,
        "update_flop_fraction": update_gflops / matmul_rate,
        "products_alone_flop_fraction": products_gflops / matmul_rate,
        "forward_flops_per_observation": forward_flops(config.hidden_size, config.num_hidden_layers, 11),
    }
    if verbose:
        r = result
        print(
            f"DQN learning steps/s: fast {r['ours_steps_per_s']:.0f}, reference "
            f"{r['reference_steps_per_s']:.0f}, SB3 {r['sb3_steps_per_s']:.0f}; fast / SB3 "
            f"{r['ratio']:.1f} (aim >= 7), reference / SB3 {r['reference_ratio']:.1f}\n"
            f"  same network ({ours_params} parameters), batch {config.batch_size}, an update every "
            f"{config.train_frequency} steps, buffer {config.buffer_size}, {config.torch_threads} "
            f"torch thread(s); median of {rounds} alternating rounds of {chunk} steps\n"
            f"  one update: fast {r['ours_update_us']:.0f} us, reference {r['reference_update_us']:.0f} us, "
            f"SB3 {r['sb3_update_us']:.0f} us\n"
            f"  fast update: {flops / 1e6:.1f} MFLOP at {update_gflops:.1f} GFLOP/s = "
            f"{r['update_flop_fraction']:.0%} of a {MATMUL_SIZE}x{MATMUL_SIZE} matmul's "
            f"{matmul_rate:.1f} GFLOP/s (aim >= 80%); its matrix products alone reach "
            f"{r['products_alone_flop_fraction']:.0%}",
            flush=True,
        )
    return result


if __name__ == "__main__":
    run()
