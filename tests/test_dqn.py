"""The deep Q-learner: the paper's network, its hand-written update, schedules, seeding,
checkpoints, and that it actually learns (the chain MDP)."""

from __future__ import annotations

import numpy as np
import pytest

from .optional import importorskip

torch = importorskip("torch")
import torch.nn.functional as F  # noqa: E402

from mediated_transfer.learners.base import Learner
from mediated_transfer.learners.dqn import DQNConfig, DQNLearner, QNetwork

from .chain_mdp import RIGHT, ChainMDP

HIDDEN = 256


def small_config(**overrides) -> DQNConfig:
    """Small, fast settings for the chain MDP (the paper's network, shorter schedules)."""
    base = dict(learning_rate=1e-3, gamma=0.9, buffer_size=2_000, learning_starts=100,
                train_frequency=1, target_update_interval=100, epsilon_decay_steps=1_000)
    return DQNConfig(**{**base, **overrides})


def random_observations(rng: np.random.Generator, n: int) -> np.ndarray:
    obs = np.zeros((n, 11))
    obs[:, :6] = rng.uniform(0.0, 20.0, (n, 6))
    obs[np.arange(n), 6 + rng.integers(0, 5, n)] = 1.0
    return obs


def fill_buffer(learner: DQNLearner, n: int, seed: int = 0, terminal_every: int = 7) -> None:
    rng = np.random.default_rng(seed)
    obs, nxt = random_observations(rng, n), random_observations(rng, n)
    for i in range(n):
        reward = float(rng.choice([0.0, 10.0, -3.0]))
        learner.buffer.add(obs[i], int(rng.integers(11)), reward, nxt[i], i % terminal_every == 0)


def run_chain(learner: DQNLearner, steps: int, max_episode_steps: int = 20) -> list[int]:
    """Let the learner explore-and-learn on the chain; returns the actions it took."""
    env, actions, t = ChainMDP(), [], 0
    obs = env.reset()
    for _ in range(steps):
        a = learner.act(obs)
        nxt, r, done = env.step(a)
        learner.observe(obs, a, r, nxt, done)
        actions.append(a)
        obs, t = nxt, t + 1
        if done or t >= max_episode_steps:
            learner.end_episode()
            obs, t = env.reset(), 0
    return actions


# --- config ---------------------------------------------------------------------------------
def test_defaults_keep_what_the_paper_fixes():
    cfg = DQNConfig()
    assert (cfg.hidden_size, cfg.num_hidden_layers) == (256, 3)
    assert (cfg.epsilon_start, cfg.epsilon_end) == (1.0, 0.1)
    assert isinstance(DQNLearner(DQNConfig(buffer_size=1_000)), Learner)


@pytest.mark.parametrize("overrides, key", [
    ({"gamma": 1.0}, "algorithm.gamma"),
    ({"gamma": -0.1}, "algorithm.gamma"),
    ({"learning_rate": -1e-3}, "algorithm.learning_rate"),
    ({"learning_rate": 0.0}, "algorithm.learning_rate"),
    ({"buffer_size": 16, "batch_size": 32, "learning_starts": 0}, "algorithm.buffer_size"),
    ({"learning_starts": 5_000, "buffer_size": 1_000}, "algorithm.learning_starts"),
    ({"epsilon_end": 1.5}, "algorithm.epsilon_end"),
    ({"epsilon_start": -0.1}, "algorithm.epsilon_start"),
    ({"batch_size": 0}, "algorithm.batch_size"),
    ({"train_frequency": 2.5}, "algorithm.train_frequency"),
    ({"max_grad_norm": 0.0}, "algorithm.max_grad_norm"),
    ({"huber_delta": -1.0}, "algorithm.huber_delta"),
])
def test_bad_hyperparameters_raise_naming_the_key(overrides, key):
    with pytest.raises(ValueError, match=key.replace(".", r"\.")):
        DQNConfig(**overrides)


# --- network --------------------------------------------------------------------------------
def test_network_is_the_papers_architecture():
    net = QNetwork(generator=torch.Generator().manual_seed(0))
    # 6 -> 256 -> 256 -> 256, then [256 + 5] -> 11.
    assert net.shapes == [(HIDDEN, 6), (HIDDEN, HIDDEN), (HIDDEN, HIDDEN), (11, HIDDEN + 5)]
    expected = (6 * 256 + 256) + 2 * (256 * 256 + 256) + (261 * 11 + 11)
    assert net.flat.numel() == expected
    # The one-hot enters only at the last layer, linearly: switching the active picking location
    # changes Q by the difference of two head columns, whatever the distances.
    head_w = net.layers()[-1][0]
    obs = torch.tensor(random_observations(np.random.default_rng(1), 4), dtype=torch.float32)
    a, b = obs.clone(), obs.clone()
    a[:, 6:], b[:, 6:] = 0.0, 0.0
    a[:, 6 + 1], b[:, 6 + 4] = 1.0, 1.0
    with torch.no_grad():
        diff = net(a) - net(b)
    expected_diff = (head_w[:, HIDDEN + 1] - head_w[:, HIDDEN + 4]).detach().expand(4, -1)
    torch.testing.assert_close(diff, expected_diff, atol=1e-6, rtol=0)


def test_greedy_action_is_the_argmax_of_the_network():
    learner = DQNLearner(small_config(), seed=3)
    obs = random_observations(np.random.default_rng(2), 50)
    with torch.no_grad():
        q = learner.network(torch.tensor(obs, dtype=torch.float32)).numpy()
    for o, row in zip(obs, q):
        np.testing.assert_allclose(learner.q_values(o), row, rtol=1e-5, atol=1e-5)
        assert learner.act(o, explore=False) == int(np.argmax(row))


# --- the update -----------------------------------------------------------------------------
@pytest.mark.parametrize("max_grad_norm", [None, 0.05])
def test_update_matches_autograd_and_torch_adam(max_grad_norm):
    """Three updates of the hand-written pass equal Huber loss + autograd + torch's Adam (and
    clip_grad_norm_ when clipping: 0.05 is below the gradient norms here, so it bites)."""
    cfg = small_config(batch_size=16, max_grad_norm=max_grad_norm, huber_delta=1.0)
    learner = DQNLearner(cfg, seed=1)
    fill_buffer(learner, 200)
    with torch.no_grad():  # a target network different from the online one
        learner.target_network.flat.add_(0.05 * torch.randn(learner.target_network.flat.shape,
                                                            generator=torch.Generator().manual_seed(9)))
    reference = QNetwork(cfg.hidden_size, cfg.num_hidden_layers, 11)
    with torch.no_grad():
        reference.flat.copy_(learner.network.flat)
    optimizer = torch.optim.Adam(reference.parameters(), lr=cfg.learning_rate)
    for _ in range(3):
        batch = learner.buffer.sample(learner.rng)
        obs, nxt = batch["observations"].clone(), batch["next_observations"].clone()
        actions, rewards = batch["actions"].long(), batch["rewards"].clone()
        with torch.no_grad():
            y = rewards + cfg.gamma * batch["bootstrap"] * learner.target_network(nxt).max(1).values
        q = reference(obs).gather(1, actions[:, None]).squeeze(1)
        loss = F.huber_loss(q, y, delta=cfg.huber_delta)
        optimizer.zero_grad()
        loss.backward()
        unclipped = reference.flat.grad.clone()
        norm = float(unclipped.norm())
        if max_grad_norm is not None:
            torch.nn.utils.clip_grad_norm_(reference.parameters(), max_grad_norm)
            assert norm > max_grad_norm
        optimizer.step()

        ours_loss = learner.update(batch)
        assert ours_loss == pytest.approx(loss.item(), rel=1e-5)
        assert learner.update.grad_norm == pytest.approx(norm, rel=1e-4)
        # (float32 sums in another order, on weights that differ by rounding from step 2 on)
        torch.testing.assert_close(learner.update.grad_flat, unclipped,
                                   rtol=1e-4, atol=1e-5 * float(unclipped.abs().max()))
        torch.testing.assert_close(learner.network.flat.detach(), reference.flat.detach(),
                                   atol=1e-2 * cfg.learning_rate, rtol=1e-5)


def test_terminal_transitions_do_not_bootstrap():
    learner = DQNLearner(small_config(batch_size=1, buffer_size=1, learning_starts=1), seed=0)
    obs = random_observations(np.random.default_rng(0), 2)
    with torch.no_grad():  # make the target network's values large, so bootstrapping would show
        learner.target_network.layers()[-1][1].fill_(100.0)
    learner.buffer.add(obs[0], 3, 2.0, obs[1], terminated=True)
    q_sa = float(learner.q_values(obs[0])[3])
    loss = learner.update(learner.buffer.sample(learner.rng))
    td = q_sa - 2.0  # y = r, no gamma * max Q_target
    assert loss == pytest.approx(0.5 * td**2 if abs(td) <= 1 else abs(td) - 0.5, rel=1e-5)


# --- schedules ------------------------------------------------------------------------------
def test_epsilon_decays_linearly_from_start_to_end():
    learner = DQNLearner(small_config(epsilon_decay_steps=10, learning_starts=1_000), seed=0)
    env = ChainMDP()
    seen = []
    for _ in range(15):
        seen.append(learner.epsilon)
        obs = env.observation(0)
        learner.observe(obs, 1, 0.0, obs, False)
    expected = [1.0 - 0.9 * min(k, 10) / 10 for k in range(15)]
    np.testing.assert_allclose(seen, expected)
    assert learner.stats["epsilon"] == pytest.approx(0.1)


def test_exploration_follows_epsilon():
    obs = ChainMDP().observation(0)
    greedy_only = DQNLearner(small_config(epsilon_start=0.0, epsilon_end=0.0), seed=0)
    greedy = greedy_only.act(obs, explore=False)
    assert all(greedy_only.act(obs) == greedy for _ in range(200))
    random_only = DQNLearner(small_config(epsilon_start=1.0, epsilon_end=1.0), seed=0)
    counts = np.bincount([random_only.act(obs) for _ in range(2_200)], minlength=11)
    assert counts.min() > 120  # every action, about 200 times each


def test_target_network_copies_every_tau_steps_and_updates_start_at_e_start():
    tau, start = 5, 8
    learner = DQNLearner(small_config(target_update_interval=tau, learning_starts=start,
                                      batch_size=4, train_frequency=2), seed=0)
    rng = np.random.default_rng(0)
    obs = random_observations(rng, 40)
    initial = learner.network.flat.detach().clone()
    snapshot = learner.target_network.flat.detach().clone()
    for step in range(1, 31):
        learner.observe(obs[step], int(rng.integers(11)), float(rng.choice([0.0, 10.0])),
                        obs[step + 1], False)
        online, target = learner.network.flat.detach(), learner.target_network.flat.detach()
        # Updates: at every 2nd step once the buffer holds E_start transitions.
        assert learner.stats["updates"] == (0 if step < start else (step - start) // 2 + 1)
        if step < start:
            assert torch.equal(online, initial)
        if step % tau == 0:
            assert torch.equal(target, online)
            snapshot = target.clone()
        else:
            assert torch.equal(target, snapshot)
            if step >= start and step % 2 == 0:  # updated since the last copy
                assert not torch.equal(target, online)
    assert learner.stats["target_syncs"] == 30 // tau


# --- determinism and checkpoints --------------------------------------------------------------
def test_same_seed_gives_identical_weights_and_actions():
    a, b, c = (DQNLearner(small_config(), seed=s) for s in (7, 7, 8))
    actions_a, actions_b, actions_c = (run_chain(x, 400) for x in (a, b, c))
    assert actions_a == actions_b
    assert torch.equal(a.network.flat, b.network.flat)
    assert torch.equal(a.target_network.flat, b.target_network.flat)
    assert not torch.equal(a.network.flat, c.network.flat)
    assert actions_a != actions_c


def test_a_larger_buffer_changes_nothing_until_the_smaller_one_is_full():
    # The DQN failure ablation's by-seed table relies on it: its arms that differ only in the
    # buffer are the same run up to the step at which the smaller buffer is full.
    small, large = (DQNLearner(small_config(buffer_size=n), seed=3) for n in (300, 5_000))
    assert run_chain(small, 300) == run_chain(large, 300)
    assert torch.equal(small.network.flat, large.network.flat)
    run_chain(small, 300), run_chain(large, 300)
    assert not torch.equal(small.network.flat, large.network.flat)


def test_greedy_act_leaves_the_learner_untouched():
    learner = DQNLearner(small_config(), seed=0)
    run_chain(learner, 150)
    rng_state, stats = learner.rng.bit_generator.state, learner.stats
    for o in random_observations(np.random.default_rng(5), 20):
        learner.act(o, explore=False)
    assert learner.rng.bit_generator.state == rng_state
    assert learner.stats == stats


def test_checkpoint_resumes_exactly(tmp_path):
    learner = DQNLearner(small_config(), seed=4)
    run_chain(learner, 300)
    path = tmp_path / "dqn.pt"
    torch.save(learner.state_dict(), path)
    resumed = DQNLearner(small_config(), seed=99)
    resumed.load_state_dict(torch.load(path, weights_only=True))
    assert resumed.stats == learner.stats
    # Same future: same exploration draws, batches and updates.
    assert run_chain(resumed, 200) == run_chain(learner, 200)
    assert torch.equal(resumed.network.flat, learner.network.flat)
    assert torch.equal(resumed.update.adam_sq_mean, learner.update.adam_sq_mean)


def test_checkpoint_of_another_architecture_is_refused():
    state = DQNLearner(small_config(hidden_size=32), seed=0).state_dict()
    with pytest.raises(ValueError, match="hidden_size"):
        DQNLearner(small_config(), seed=0).load_state_dict(state)


# --- learning -------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", [0, 1])
def test_learns_the_chain(seed):
    """A few thousand steps suffice for the optimal greedy policy (always RIGHT) and Q close to
    Q* (values up to 10; an untrained network is off by several units)."""
    cfg = small_config()
    learner = DQNLearner(cfg, seed=seed)
    run_chain(learner, 2_000)
    env = ChainMDP()
    states = range(env.n - 1)
    assert [learner.act(env.observation(s), explore=False) for s in states] == [RIGHT] * len(states)
    q = np.array([learner.q_values(env.observation(s)) for s in states])
    assert np.abs(q - env.q_star(cfg.gamma)).max() < 1.0


# --- the benchmark's SB3 twin -----------------------------------------------------------------
def test_sb3_twin_computes_the_same_network():
    """The bench compares against SB3 with a features extractor meant to reproduce QNetwork:
    with our weights copied in, it must compute our Q-values."""
    import gymnasium

    from mediated_transfer.bench.dqn_speed import make_sb3_dqn

    class Spaces(gymnasium.Env):
        observation_space = gymnasium.spaces.Box(0.0, 40.0, (11,), np.float64)
        action_space = gymnasium.spaces.Discrete(11)

        def reset(self, *, seed=None, options=None):
            return np.zeros(11), {}

        def step(self, action):
            return np.zeros(11), 0.0, False, False, {}

    cfg = DQNConfig(buffer_size=1_000)
    sb3 = make_sb3_dqn(cfg, Spaces(), seed=0)
    ours = DQNLearner(cfg, seed=0)
    hidden = [m for m in sb3.q_net.features_extractor.hidden if isinstance(m, torch.nn.Linear)]
    linears = hidden + [m for m in sb3.q_net.q_net if isinstance(m, torch.nn.Linear)]
    assert len(linears) == len(ours.network.shapes)
    with torch.no_grad():
        for layer, (w, b) in zip(linears, ours.network.layers()):
            layer.weight.copy_(w)
            layer.bias.copy_(b)
    obs = random_observations(np.random.default_rng(3), 8)
    with torch.no_grad():
        theirs = sb3.q_net(torch.tensor(obs, dtype=torch.float32)).numpy()
    np.testing.assert_allclose(theirs, [ours.q_values(o) for o in obs], rtol=1e-5, atol=1e-5)


@pytest.mark.slow
def test_speed_bench_runs_side_by_side():
    """`make bench`'s DQN part end to end on a tiny budget (no timing asserted)."""
    from mediated_transfer.bench import dqn_speed

    cfg = DQNConfig(buffer_size=1_000, learning_starts=100)
    result = dqn_speed.run(100, config=cfg, rounds=2, warmup_steps=200, verbose=False)
    assert result["timed_steps"] == 100 and result["buffer_size"] == 1_000
    assert result["network_parameters"] == DQNLearner(cfg).network.flat.numel()
    for key in ("ours_steps_per_s", "sb3_steps_per_s", "ratio", "update_flop_fraction"):
        assert np.isfinite(result[key]) and result[key] > 0


# --- the fast kernels against the reference (algorithm.kernels) ------------------------------
def twin_learners(seed: int = 1, **overrides) -> tuple[DQNLearner, DQNLearner]:
    """A fast and a reference learner with the same weights, replay contents and random state,
    and a target network that differs from the online one."""
    fast = DQNLearner(small_config(kernels="fast", **overrides), seed=seed)
    reference = DQNLearner(small_config(kernels="reference", **overrides), seed=seed)
    for learner in (fast, reference):
        fill_buffer(learner, 200)
        with torch.no_grad():
            learner.target_network.flat.add_(0.05 * torch.randn(
                learner.target_network.flat.shape, generator=torch.Generator().manual_seed(9)))
    return fast, reference


@pytest.mark.parametrize("max_grad_norm", [None, 0.05])
@pytest.mark.parametrize("seed", [1, 2])
def test_fast_update_equals_the_reference(max_grad_norm, seed):
    """Step by step, on the same batches: the same loss, gradient norm (before clipping; 0.05
    bites), Adam state and weights, up to float32 rounding. Weights are compared against one
    Adam step's size: Adam divides by sqrt(v), so a gradient element that is float32 noise
    (a sum cancelling to ~1e-7) still moves its weight by a rounding-dependent fraction of lr."""
    fast, reference = twin_learners(seed, batch_size=16, max_grad_norm=max_grad_norm)
    lr = fast.config.learning_rate
    for _ in range(4):
        batch = fast.buffer.sample(fast.rng)
        same = reference.buffer.sample(reference.rng)
        np.testing.assert_array_equal(batch["rows"], same["rows"])
        assert fast.update(batch) == pytest.approx(reference.update(same), rel=1e-5)
        assert fast.update.grad_norm == pytest.approx(reference.update.grad_norm, rel=1e-4)
        assert fast.update.adam_steps == reference.update.adam_steps
        torch.testing.assert_close(fast.update.adam_mean, reference.update.adam_mean,
                                   rtol=1e-3, atol=1e-5 * float(reference.update.adam_mean.abs().max()))
        difference = (fast.network.flat - reference.network.flat).abs().detach()
        assert float(difference.max()) < 0.05 * lr
        assert float(difference.mean()) < 1e-4 * lr


def test_reference_greedy_action_equals_the_fast_one():
    fast, reference = twin_learners(3)
    for o in random_observations(np.random.default_rng(4), 30):
        np.testing.assert_allclose(fast.q_values(o), reference.q_values(o), rtol=1e-5, atol=1e-5)
        assert fast.act(o, explore=False) == reference.act(o, explore=False)


def test_fast_update_sees_a_changed_target_network():
    """The fast kernels keep the target network transposed; any write to it must reach them."""
    fast, reference = twin_learners(5)
    for learner in (fast, reference):
        learner.update(learner.buffer.sample(learner.rng))
        with torch.no_grad():
            learner.target_network.flat.mul_(-2.0)
    assert fast.update(fast.buffer.sample(fast.rng)) == pytest.approx(
        reference.update(reference.buffer.sample(reference.rng)), rel=1e-5)


@pytest.mark.parametrize("saved, loaded", [("fast", "reference"), ("reference", "fast")])
def test_checkpoints_move_between_kernels(saved, loaded):
    learner = DQNLearner(small_config(kernels=saved), seed=4)
    run_chain(learner, 300)
    resumed = DQNLearner(small_config(kernels=loaded), seed=99)
    resumed.load_state_dict(learner.state_dict())
    assert resumed.stats == learner.stats
    assert torch.equal(resumed.network.flat, learner.network.flat)
    assert torch.equal(resumed.update.adam_sq_mean, learner.update.adam_sq_mean)
    assert resumed.update.adam_steps == learner.update.adam_steps
    # The next update starts from the same state: equal up to float32 rounding.
    assert resumed.update(resumed.buffer.sample(resumed.rng)) == pytest.approx(
        learner.update(learner.buffer.sample(learner.rng)), rel=1e-5)


@pytest.mark.slow
def test_reference_kernels_learn_the_chain():
    learner = DQNLearner(small_config(kernels="reference"), seed=0)
    run_chain(learner, 2_000)
    env = ChainMDP()
    assert [learner.act(env.observation(s), explore=False) for s in range(env.n - 1)] == [RIGHT] * (env.n - 1)


def test_unknown_kernels_are_refused_naming_the_choices():
    with pytest.raises(ValueError, match=r"algorithm\.kernels must be fast or reference"):
        DQNConfig(kernels="turbo")
