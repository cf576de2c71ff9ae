"""The deep Q-learner's hyperparameters and the network sizes they imply (Sec. V, Fig. 2).

Apart from dqn.py so that composing and checking a config, and estimating a learner's memory,
need no torch: a linear run never imports it.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

from ..env.sensors import PAPER_SENSORS, Sensors
from ..env.task import NUM_DISTANCES, OBSERVATION_SIZE

NUM_BINARY = OBSERVATION_SIZE - NUM_DISTANCES
"""The paper's one-hot width (5); a world's own is ``len(sensors.picking_locations)``."""
KERNELS = ("fast", "reference")


# --------------------------------------------------------------------------------------------
# Config
# --------------------------------------------------------------------------------------------
MAX_TORCH_THREADS = 1024
"""torch refuses absurd thread counts only when the learner is built; refuse them up front."""


@dataclass(frozen=True)
class DQNConfig:
    """Hyperparameters of the deep Q-learner.

    PROVISIONAL defaults: the paper's Table I (its tuned values) is lost. These are common DQN
    practice (Mnih et al. 2015 scaled to a 500k-step budget; Stable-Baselines3 defaults) until
    the tuning issue publishes this project's own Table I.
    """

    learning_rate: float = 1e-4
    """Adam's constant step size alpha (SB3 default)."""
    gamma: float = 0.99
    """Discount factor, in [0, 1)."""
    batch_size: int = 32
    """Transitions per gradient update (Mnih et al.)."""
    buffer_size: int = 100_000
    """Replay buffer capacity E (transitions; the oldest is overwritten first)."""
    learning_starts: int = 1_000
    """E_start: updates begin once the buffer holds this many (and at least batch_size)."""
    train_frequency: int = 4
    """One gradient update every this many learning steps (Mnih et al.)."""
    target_update_interval: int = 1_000
    """tau: the target network receives a copy of the online weights every tau learning steps."""
    epsilon_start: float = 1.0
    """Exploration rate at learning step 0 (paper: 1)."""
    epsilon_end: float = 0.1
    """Exploration rate after the decay (paper: 0.1)."""
    epsilon_decay_steps: int = 50_000
    """Learning steps over which epsilon falls linearly from start to end (10 % of 500k)."""
    hidden_size: int = 256
    """Units per hidden layer (paper: 256)."""
    num_hidden_layers: int = 3
    """Fully connected ReLU layers on the 6 distances (paper: 3)."""
    huber_delta: float = 1.0
    """The TD error's loss is quadratic inside [-delta, delta] and linear outside; inf: quadratic
    everywhere (the squared TD error; config/finite.py lets this key be inf)."""
    max_grad_norm: float | None = 10.0
    """Clip the gradient's global L2 norm to this (SB3 default); None or inf: no clipping."""
    adam_beta1: float = 0.9
    """Adam's decay of the gradient mean (torch default)."""
    adam_beta2: float = 0.999
    """Adam's decay of the squared-gradient mean (torch default)."""
    adam_epsilon: float = 1e-8
    """Adam's denominator guard (torch default)."""
    torch_threads: int = 1
    """torch intra-op threads (process-wide); 1 because runs are parallelised across processes."""
    kernels: str = "fast"
    """How the update and the greedy action are computed: ``fast`` (hand-written kernels,
    dqn_kernels.py) or ``reference`` (autograd and torch.optim.Adam, ~3x slower). The same
    functions: curves differ only by float32 rounding."""

    def __post_init__(self) -> None:
        def fail(key: str, allowed: str) -> None:
            raise ValueError(f"algorithm.{key} must be {allowed}, got {getattr(self, key)!r}")

        for f in fields(self):  # values from Python are not typed by Hydra
            value = getattr(self, f.name)
            if f.type.startswith("float") and value is not None and (
                    isinstance(value, bool) or not isinstance(value, (int, float))):
                fail(f.name, "a number")
        for key in ("batch_size", "buffer_size", "train_frequency", "target_update_interval",
                    "hidden_size", "num_hidden_layers", "torch_threads"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                fail(key, "an integer >= 1")
        for key in ("learning_starts", "epsilon_decay_steps"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                fail(key, "an integer >= 0")
        if self.torch_threads > MAX_TORCH_THREADS:
            fail("torch_threads", f"at most {MAX_TORCH_THREADS}")
        if not 0.0 <= self.gamma < 1.0:
            fail("gamma", "in [0, 1)")
        if not (self.learning_rate > 0 and math.isfinite(self.learning_rate)):
            fail("learning_rate", "a finite number > 0")
        for key in ("epsilon_start", "epsilon_end"):
            if not 0.0 <= getattr(self, key) <= 1.0:
                fail(key, "in [0, 1]")
        if not self.huber_delta > 0:
            fail("huber_delta", "> 0")
        if self.max_grad_norm is not None and not self.max_grad_norm > 0:
            fail("max_grad_norm", "> 0 or None (no clipping)")
        for key in ("adam_beta1", "adam_beta2"):
            if not 0.0 <= getattr(self, key) < 1.0:
                fail(key, "in [0, 1)")
        if not self.adam_epsilon > 0:
            fail("adam_epsilon", "> 0")
        if self.kernels not in KERNELS:
            fail("kernels", " or ".join(KERNELS))
        if self.buffer_size < self.batch_size:
            raise ValueError(
                f"algorithm.buffer_size ({self.buffer_size}) must be >= algorithm.batch_size "
                f"({self.batch_size}): the replay buffer must hold at least one batch"
            )
        if self.learning_starts > self.buffer_size:
            raise ValueError(
                f"algorithm.learning_starts ({self.learning_starts}) must be <= algorithm.buffer_size "
                f"({self.buffer_size}), or learning would never start"
            )

    def to_dict(self) -> dict:
        return asdict(self)


# --------------------------------------------------------------------------------------------
# Network sizes
# --------------------------------------------------------------------------------------------
def layer_shapes(hidden_size: int, num_hidden_layers: int, num_actions: int,
                 sensors: Sensors = PAPER_SENSORS) -> list[tuple[int, int]]:
    """(out, in) of each linear layer: the hidden layers on the world's distances, then the
    head on [last hidden layer, one-hot picking location] (``sensors``: the world's layout)."""
    shapes = [(hidden_size, sensors.num_distances)]
    shapes += [(hidden_size, hidden_size)] * (num_hidden_layers - 1)
    shapes.append((num_actions, hidden_size + len(sensors.picking_locations)))
    return shapes


def forward_flops(hidden_size: int, num_hidden_layers: int, num_actions: int,
                  sensors: Sensors = PAPER_SENSORS) -> int:
    """Floating-point operations (2 per multiply-add) of one observation's forward pass."""
    shapes = layer_shapes(hidden_size, num_hidden_layers, num_actions, sensors)
    return sum(2 * out * inp for out, inp in shapes)


def update_flops(config: DQNConfig, num_actions: int = 11, sensors: Sensors = PAPER_SENSORS) -> int:
    """Nominal FLOPs of one update: the online forward of the batch, its backward (~2x) and the
    target network's forward, i.e. 4 forward passes of the batch."""
    return 4 * config.batch_size * forward_flops(config.hidden_size, config.num_hidden_layers,
                                                 num_actions, sensors)
