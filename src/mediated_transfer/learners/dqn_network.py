"""The deep Q-learner's network (Fig. 2): distances -> hidden ReLU layers; the one-hot picking
location concatenated to the last; linear -> Q. Its own module so that the fast kernels
(dqn_kernels.py) and the learner (dqn.py) both build on it without importing each other.
"""

from __future__ import annotations

import math
from typing import Any

try:
    import torch
    import torch.nn.functional as F
    from torch import nn
except ModuleNotFoundError:  # no deep extra: the config and the shapes import, a DQN cannot be built
    class _NoTorch:
        Module = object  # torch.nn.Module, so that the classes below can be defined

        def __getattr__(self, name: str) -> Any:
            raise ModuleNotFoundError("algorithm=dqn needs torch: pip install 'mediated-transfer[deep]' "
                                      "(make install does; docs/install.md)")

    torch = F = nn = _NoTorch()  # type: ignore[assignment]

from ..env.sensors import PAPER_SENSORS, Sensors
from .dqn_config import layer_shapes


class QNetwork(nn.Module):
    """Fig. 2: distances -> hidden ReLU layers; one-hot concatenated to the last; linear -> Q.
    ``sensors``: the world's layout (env/sensors.py; the paper's: 6 distances, a 5-dim one-hot).

    All weights and biases are slices of one flat parameter vector (layer by layer: weight
    (out, in), then bias), which makes copying, checkpointing and the Adam step one vector
    operation each. Initialisation is torch's ``nn.Linear`` default, U(-1/sqrt(in), 1/sqrt(in)),
    drawn from the given generator.
    """

    def __init__(self, hidden_size: int = 256, num_hidden_layers: int = 3, num_actions: int = 11,
                 generator: torch.Generator | None = None, sensors: Sensors = PAPER_SENSORS):
        super().__init__()
        # The world's layout: its distances feed the hidden layers, its one-hot the head.
        self.num_distances = sensors.num_distances
        self.shapes = layer_shapes(hidden_size, num_hidden_layers, num_actions, sensors)
        self.flat = nn.Parameter(torch.empty(sum(o * i + o for o, i in self.shapes)))
        with torch.no_grad():
            for (out, inp), (w, b) in zip(self.shapes, self.layers()):
                bound = 1.0 / math.sqrt(inp)
                for t in (w, b):
                    t.copy_(torch.rand(t.shape, generator=generator) * (2 * bound) - bound)

    def layers(self, flat: torch.Tensor | None = None) -> list[tuple[torch.Tensor, torch.Tensor]]:
        """(weight, bias) views of each layer into ``flat`` (default: this network's)."""
        flat = self.flat if flat is None else flat
        views, start = [], 0
        for out, inp in self.shapes:
            w = flat[start:start + out * inp].view(out, inp)
            start += out * inp
            views.append((w, flat[start:start + out]))
            start += out
        return views

    def forward(self, observation: torch.Tensor) -> torch.Tensor:
        distances, picking = observation[:, :self.num_distances], observation[:, self.num_distances:]
        *hidden, (head_w, head_b) = self.layers()
        h = distances
        for w, b in hidden:
            h = F.relu(F.linear(h, w, b))
        return F.linear(torch.cat([h, picking], dim=1), head_w, head_b)
