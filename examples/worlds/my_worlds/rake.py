"""A rake: a T-shaped mediator. Its handle runs from the junction to M1; its head crosses the
handle's end at right angles, with M2 and M3 at the head's two ends (its own picking locations).

    python -m mediated_transfer env=rake hydra.searchpath=[pkg://my_worlds.conf]
"""

from __future__ import annotations

from dataclasses import dataclass

from mediated_transfer.env import WorldConfig
from mediated_transfer.env.paper import PaperWorld


@dataclass(frozen=True)
class RakeConfig(WorldConfig):
    rake_head_length: float = 6.0
    """Length of the rake's head, the T's crossbar (the handle is tool_handle_length)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        if not 0.0 < self.rake_head_length <= 2 * self.interaction_radius:
            raise ValueError(f"env.rake_head_length must lie in (0, {2 * self.interaction_radius:g}], "
                             f"got {self.rake_head_length!r}")

    @property
    def tool_points(self):
        # Body frame: the junction at the origin, the handle along +x, the head along y.
        half = self.rake_head_length / 2
        return (self.tool_handle_length, 0.0), (0.0, -half), (0.0, half)

    @property
    def tool_segments(self):
        half = self.rake_head_length / 2
        return (((0.0, 0.0), (self.tool_handle_length, 0.0), self.tool_handle_length),
                ((0.0, -half), (0.0, half), self.rake_head_length))


class RakeWorld(PaperWorld):
    """The paper's world with a rake for the L: the same tasks, sensors and actions."""

    config_class = RakeConfig
    scripted_policy = None  # the project's scripted tool policy knows the L only
