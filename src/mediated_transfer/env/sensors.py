"""What a world's sensor vector holds, in order: distances first, then the one-hot of the
active picking location (the layout of the paper's eq. 2). Representations and networks read
the layout from here, so a world with another sensor brings its own."""

from __future__ import annotations

from dataclasses import dataclass

DISTANCE_KINDS = ("target", "origin")
"""What a distance measures: to the target (|MiT|, up to 2 world radii) or to the origin O
(|MiO|, up to one world radius); representations bin each kind over its own range."""


@dataclass(frozen=True)
class Sensors:
    distances: tuple[str, ...]
    """Names of the distance entries, in order (the paper: M1T M2T M3T M1O M2O M3O)."""
    kinds: tuple[str, ...]
    """One of DISTANCE_KINDS per distance."""
    picking_locations: tuple[str, ...]
    """Names of the picking locations, the order of the one-hot (the paper: M1 M2 M3 T O)."""

    def __post_init__(self) -> None:
        if len(self.kinds) != len(self.distances):
            raise ValueError(f"sensors: {len(self.distances)} distances but {len(self.kinds)} kinds")
        bad = sorted(set(self.kinds) - set(DISTANCE_KINDS))
        if bad:
            raise ValueError(f"sensors: unknown distance kind(s) {', '.join(bad)}; allowed: {', '.join(DISTANCE_KINDS)}")

    @property
    def num_distances(self) -> int:
        return len(self.distances)

    @property
    def size(self) -> int:
        """Length of the sensor vector (the observation)."""
        return len(self.distances) + len(self.picking_locations)

    def with_distance(self, name: str, kind: str) -> "Sensors":
        """This layout with one more distance, after the others (before the one-hot)."""
        return Sensors((*self.distances, name), (*self.kinds, kind), self.picking_locations)


PAPER_SENSORS = Sensors(("M1T", "M2T", "M3T", "M1O", "M2O", "M3O"), ("target",) * 3 + ("origin",) * 3,
                        ("M1", "M2", "M3", "T", "O"))
"""Eq. (2) of the paper: 6 distances, then the one-hot of 5 picking locations (11 entries)."""
