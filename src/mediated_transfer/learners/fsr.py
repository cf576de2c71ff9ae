"""The binary representation (FSR): an independent discretisation of each sensor entry.

310 = 6 * 50 + 5 * 2: each of the 6 distances is cut into 50 equal bins and each of the 5
binary picking-location entries into 2, one feature per bin, and exactly one feature is active
per dimension (11 of 310, all with value 1). This is RLPy's ``IndependentDiscretization``:
bin = floor((s - low) * bins / (high - low)), the top edge falling into the last bin. Distances
outside [low, high] are clipped into the border bins.

Range choice: distances that occur lie in |MiT| in [0, ~24] and |MiO| in [0, ~12] (the walls
bound them by 36 and 18, but the far ends are rare), so the defaults spend the 50 bins there:
|MiT| bins of 0.48, |MiO| bins of 0.24.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

from ..env.sensors import PAPER_SENSORS, Sensors
from ..mapping import config_from_mapping
from ._distance_ranges import check_numbers_and_ranges, check_positive_int

BINARY_BINS = 2


@dataclass(frozen=True)
class FSRConfig:
    """Independent discretisation of the 6 distances and the 5 binary entries."""

    distance_bins: int = 50
    """Bins per distance dimension (310 features in all with the defaults)."""
    tool_target_low: float = 0.0
    """Lower edge of the |MiT| bins (smaller values are clipped)."""
    tool_target_high: float = 24.0
    """Upper edge of the |MiT| bins (larger values are clipped)."""
    tool_origin_low: float = 0.0
    """Lower edge of the |MiO| bins."""
    tool_origin_high: float = 12.0
    """Upper edge of the |MiO| bins."""

    def __post_init__(self) -> None:
        check_numbers_and_ranges(self)
        check_positive_int(self, "distance_bins")

    def to_dict(self) -> dict:
        return asdict(self)


class FSRRepresentation:
    """phi(s) for the FSR: ``active_features`` writes the 11 active (index, 1.0) pairs.

    Feature order: the 50 bins of |M1T|, |M2T|, |M3T|, |M1O|, |M2O|, |M3O|, then for each of
    M1, M2, M3, T, O the pair (entry 0, entry 1).
    """

    name = "fsr"

    @classmethod
    def from_params(cls, sensors: Sensors = PAPER_SENSORS, **params) -> "FSRRepresentation":
        """``representation``'s ``_target_``: the feature map of the group's keys, for the
        world's sensor layout."""
        return cls(config_from_mapping(FSRConfig, params, "representation"), sensors)

    def __init__(self, config: FSRConfig = FSRConfig(), sensors: Sensors = PAPER_SENSORS):
        self.config = config
        self.num_features = sensors.num_distances * config.distance_bins + len(sensors.picking_locations) * BINARY_BINS
        #: Exactly one active feature per sensor entry.
        self.max_active = self._size = sensors.size
        # Each distance binned over the range of its kind: to the target, or to the origin.
        ranges = {"target": (config.tool_target_low, config.tool_target_high),
                  "origin": (config.tool_origin_low, config.tool_origin_high)}
        self._low = np.array([ranges[kind][0] for kind in sensors.kinds])
        self._high = np.array([ranges[kind][1] for kind in sensors.kinds])

    def active_features(self, observation: np.ndarray, index_out: np.ndarray, value_out: np.ndarray) -> int:
        """Write the active features of phi(s) to the buffers, indices ascending (one per entry,
        in entry order); return how many there are (11)."""
        if observation.shape != (self._size,):
            raise ValueError(f"observation must have shape ({self._size},), got {observation.shape}")
        n = _fsr_features(observation, self._low, self._high, self.config.distance_bins, index_out, value_out)
        if n < 0:
            raise ValueError(f"observation must be finite, got {observation.tolist()}")
        return n

    def features(self, observation) -> tuple[np.ndarray, np.ndarray]:
        """The active features of phi(s) as fresh (index, value) arrays (convenience)."""
        index = np.empty(self.max_active, dtype=np.int64)
        value = np.empty(self.max_active)
        n = self.active_features(np.asarray(observation, dtype=np.float64), index, value)
        return index[:n].copy(), value[:n].copy()

    def dense_features(self, observation) -> np.ndarray:
        """phi(s) as a dense 0/1 vector of length num_features."""
        index, value = self.features(observation)
        phi = np.zeros(self.num_features)
        phi[index] = value
        return phi


@njit(cache=True)
def _fsr_features(obs, low, high, bins, out_index, out_value):
    """One active bin per entry; returns 11, or -1 for a non-finite observation."""
    num_dims = low.shape[0]
    for d in range(num_dims):
        s = obs[d]
        if not np.isfinite(s):
            return -1
        s = min(max(s, low[d]), high[d])
        b = int((s - low[d]) * bins / (high[d] - low[d]))
        out_index[d] = d * bins + min(b, bins - 1)
        out_value[d] = 1.0
    offset = num_dims * bins
    for j in range(obs.shape[0] - num_dims):
        b = obs[num_dims + j]
        if not np.isfinite(b):
            return -1
        # Two bins over [0, 1] as in RLPy's discretisation: entries >= 0.5 fall in the upper one.
        out_index[num_dims + j] = offset + 2 * j + (1 if b >= 0.5 else 0)
        out_value[num_dims + j] = 1.0
    return obs.shape[0]
