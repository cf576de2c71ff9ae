"""The real-valued representation (RBF): Gaussian radial basis functions on a tensor-product grid.

The paper places 5 RBFs per |MiT| dimension and 3 per |MiO| dimension with sigma = 1 and counts
13829 features. That count is RLPy's uniform RBF grid (``grid_bins=[5,5,5,3,3,3]``,
``include_border=True``): each dimension gets ``bins + 1`` centres at
``linspace(low, high, bins + 1)``, every combination of centres is one Gaussian
(6^3 * 4^3 = 13824), and the 5 binary picking-location entries of the sensor vector are appended
as they are: 13824 + 5 = 13829.

Each Gaussian is RLPy's ``exp(-sum_d (s_d - mu_d)^2 / (2 sigma^2))``. With ``normalize`` (RLPy's
``normalize=True``, as in its tuned Q-learning RBF examples, e.g. ``examples/cartpole2d/rbfs.py``)
the 13824 Gaussian values are divided by their sum, so the RBF block always has L1 norm 1 and
a state between centres is a blend of them; raw, a state 2 sigma from every centre in all six
dimensions would see Gaussians of at most e^-12, next to binary entries of 1.

Range choice (``tool_target_*`` / ``tool_origin_*``). The walls bound |MiT| by 36 and |MiO| by 18,
but a grid over those bounds would space centres 6-7 sigma apart, where neighbouring Gaussians
barely overlap (at most e^-4.5 of the peak halfway between them). Distances that occur lie in
|MiT| in [0, ~24] and |MiO| in [0, ~12] (the tool mostly within reach). The defaults put the
|MiT| centres on [0, 20] and the |MiO| centres on [0, 12]: both grids are then spaced 4 sigma
apart, so neighbouring Gaussians cross at 2 sigma (e^-2 = 0.14 of their peak) and every state
is covered by a blend of its nearest centres. States beyond the last centre (some target-task
starts reach |MiT| ~ 23) are not clipped: they are represented mostly by the border centres.

Sparsity. With centres 4 sigma apart only a handful of the 13824 Gaussians matter at any state.
The Gaussian is a product of 1-D factors, so per dimension we keep only the centres whose factor
is at least ``cutoff`` times that dimension's largest factor, then form the products over the
few surviving combinations (depth first, skipping hopeless branches) and drop every product below ``cutoff``
times the largest Gaussian at that state (1e-5: beyond 4.8 sigma of the closest centre). With
the defaults at most 3 centres survive per dimension and about 35 Gaussians per state on
average. The normalising sum is taken over the whole grid (it factorises into per-dimension
sums), so every kept feature equals its dense value exactly; the dropped ones weigh 4e-5 in
L1 on average, 1.2e-4 at most over 1500 realistic states, so Q(s, a) moves by no more than
that fraction of max |theta| (the tests allow 3e-4).
``dense_features`` gives the dense 13829-vector, computed from every centre, for reference.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

from ..env.sensors import PAPER_SENSORS, Sensors
from ..mapping import config_from_mapping
from ._distance_ranges import check_numbers_and_ranges, check_positive_int



@dataclass(frozen=True)
class RBFConfig:
    """RBF grid over the 6 distances, plus the 5 binary picking-location entries."""

    tool_target_bins: int = 5
    """Bins on each |MiT| dimension (paper); bins + 1 centres, borders included."""
    tool_target_low: float = 0.0
    """First |MiT| centre."""
    tool_target_high: float = 20.0
    """Last |MiT| centre (chosen: centres 4 sigma apart; see module docstring)."""
    tool_origin_bins: int = 3
    """Bins on each |MiO| dimension (paper); bins + 1 centres, borders included."""
    tool_origin_low: float = 0.0
    """First |MiO| centre."""
    tool_origin_high: float = 12.0
    """Last |MiO| centre (chosen: centres 4 sigma apart)."""
    sigma: float = 1.0
    """Standard deviation of every Gaussian, in every dimension (paper)."""
    normalize: bool = True
    """Divide the Gaussians by their sum (RLPy's ``normalize``, as in its tuned RBF examples)."""
    cutoff: float = 1e-5
    """Drop Gaussians below this fraction of the state's largest (1e-5: 4.8 sigma; 0: dense)."""

    def __post_init__(self) -> None:
        check_numbers_and_ranges(self)
        if not isinstance(self.normalize, bool):
            raise ValueError(f"representation.normalize must be true or false, got {self.normalize!r}")
        check_positive_int(self, "tool_target_bins")
        check_positive_int(self, "tool_origin_bins")
        # 1 / (2 sigma^2) must be a finite, non-zero float64.
        if not 1e-6 <= self.sigma <= 1e6:
            raise ValueError(f"representation.sigma must lie in [1e-06, 1e+06], got {self.sigma!r}")
        if not 0.0 <= self.cutoff < 1.0:
            raise ValueError(f"representation.cutoff must lie in [0, 1), got {self.cutoff!r}")

    def to_dict(self) -> dict:
        return asdict(self)


class RBFRepresentation:
    """phi(s) for the RBF grid: ``active_features`` fills the sparse (index, value) pairs.

    Feature order follows RLPy: Gaussians in row-major order of their centre indices (the first
    |MiT| dimension varies slowest), then the 5 binary entries M1, M2, M3, T, O.
    """

    name = "rbf"

    @classmethod
    def from_params(cls, sensors: Sensors = PAPER_SENSORS, **params) -> "RBFRepresentation":
        """``representation``'s ``_target_``: the feature map of the group's keys, for the
        world's sensor layout."""
        return cls(config_from_mapping(RBFConfig, params, "representation"), sensors)

    def __init__(self, config: RBFConfig = RBFConfig(), sensors: Sensors = PAPER_SENSORS):
        self.config = config
        # Each distance gets the grid of its kind: to the target (|MiT|) or to the origin.
        grid = {"target": (config.tool_target_bins, config.tool_target_low, config.tool_target_high),
                "origin": (config.tool_origin_bins, config.tool_origin_low, config.tool_origin_high)}
        bins, lows, highs = (list(column) for column in zip(*(grid[kind] for kind in sensors.kinds)))
        num_distances, self._size = sensors.num_distances, sensors.size
        self.centres_per_dim = [np.linspace(lo, hi, b + 1) for lo, hi, b in zip(lows, highs, bins)]
        counts = np.array([len(c) for c in self.centres_per_dim], dtype=np.int64)
        self.num_gaussians = int(np.prod(counts))
        self.num_features = self.num_gaussians + len(sensors.picking_locations)
        #: Upper bound on the number of active features (sizes the caller's buffers).
        self.max_active = self.num_features
        # Kernel inputs: centres padded to a (6, max centres) table; per dimension the number
        # of centres and the row-major stride of its centre index.
        self._centres = np.zeros((num_distances, counts.max()))
        for d, c in enumerate(self.centres_per_dim):
            self._centres[d, : len(c)] = c
        strides = [int(np.prod(counts[d + 1:])) for d in range(num_distances)]
        self._layout = np.array([counts, strides], dtype=np.int64)
        self._inv_two_var = 1.0 / (2.0 * config.sigma**2)
        # Exponent margin: a Gaussian is kept when exp(-(E - E_min)) >= cutoff.
        self._max_gap = -math.log(config.cutoff) if config.cutoff > 0 else math.inf

    def active_features(self, observation: np.ndarray, index_out: np.ndarray, value_out: np.ndarray) -> int:
        """Write the active features of phi(s) to the buffers, indices ascending; return how
        many there are."""
        if observation.shape != (self._size,):
            raise ValueError(f"observation must have shape ({self._size},), got {observation.shape}")
        n = _rbf_features(observation, self._centres, self._layout, self._inv_two_var, self._max_gap,
                          self.config.normalize, index_out, value_out)
        if n < 0:
            raise ValueError(f"observation must be finite, got {observation.tolist()}")
        return n

    def features(self, observation) -> tuple[np.ndarray, np.ndarray]:
        """The active features of phi(s) as fresh (index, value) arrays (convenience)."""
        index = np.empty(self.max_active, dtype=np.int64)
        value = np.empty(self.max_active)
        n = self.active_features(np.asarray(observation, dtype=np.float64), index, value)
        return index[:n].copy(), value[:n].copy()

    def centres(self) -> np.ndarray:
        """All Gaussian centres, shape (num_gaussians, 6), in feature order."""
        grids = np.meshgrid(*self.centres_per_dim, indexing="ij")
        return np.stack([g.ravel() for g in grids], axis=1)

    def dense_features(self, observation) -> np.ndarray:
        """Reference phi(s): all 13829 entries, from every centre, without truncation (slow)."""
        s = np.asarray(observation, dtype=np.float64)
        d = len(self.centres_per_dim)
        exponent = np.sum(((s[:d] - self.centres()) / self.config.sigma) ** 2, axis=1) / 2
        if self.config.normalize:
            # Shifting the exponents cancels in the ratio and keeps far states from underflowing.
            g = np.exp(-(exponent - exponent.min()))
            g /= g.sum()
        else:
            g = np.exp(-exponent)
        return np.concatenate([g, s[d:]])


@njit(cache=True)
def _rbf_features(obs, centres, layout, inv_two_var, max_gap, normalize, out_index, out_value):
    """Sparse RBF features in ascending index order; returns the count, or -1 for a non-finite
    observation.

    Works with exponent gaps relative to the closest centre (the largest Gaussian has gap 0),
    which keeps far-away states from underflowing before normalisation.
    """
    counts, strides = layout[0], layout[1]
    num_dims, max_count = centres.shape
    num_gaussians = counts[0] * strides[0]
    # Per dimension: the kept centres' indices, exponent gaps and 1-D factors.
    kept = np.empty(num_dims, dtype=np.int64)
    kept_k = np.empty((num_dims, max_count), dtype=np.int64)
    kept_e = np.empty((num_dims, max_count))
    kept_g = np.empty((num_dims, max_count))
    # Depth-first state per level: next entry to try and the partial product's gap/value/index.
    pos = np.empty(num_dims, dtype=np.int64)
    prefix_index = np.empty(num_dims, dtype=np.int64)
    prefix_gap = np.empty(num_dims)
    prefix_value = np.empty(num_dims)
    min_total = 0.0
    grid_sum = 1.0  # sum of all relative Gaussians: the product of the per-dimension sums
    # Per dimension: gaps to the closest centre; keep the centres within max_gap (in order).
    for d in range(num_dims):
        s = obs[d]
        if not np.isfinite(s):
            return -1
        best = np.inf
        for k in range(counts[d]):
            diff = s - centres[d, k]
            best = min(best, diff * diff * inv_two_var)
        m = 0
        dim_sum = 0.0
        for k in range(counts[d]):
            diff = s - centres[d, k]
            gap = diff * diff * inv_two_var - best
            factor = np.exp(-gap)  # the relative 1-D factor; a Gaussian is their product
            dim_sum += factor
            if gap <= max_gap:
                kept_k[d, m] = k
                kept_e[d, m] = gap
                kept_g[d, m] = factor
                m += 1
        kept[d] = m
        min_total += best
        grid_sum *= dim_sum
    # Depth-first over the kept centres, dimension by dimension (so indices come out in
    # ascending order), skipping every branch whose summed gap already exceeds max_gap.
    n = 0
    last = num_dims - 1
    d = 0
    pos[0] = 0
    prefix_gap[0] = 0.0
    prefix_value[0] = 1.0
    prefix_index[0] = 0
    while d >= 0:
        if pos[d] == kept[d]:
            d -= 1
            continue
        j = pos[d]
        pos[d] += 1
        gap = prefix_gap[d] + kept_e[d, j]
        if gap > max_gap:
            continue
        value = prefix_value[d] * kept_g[d, j]
        index = prefix_index[d] + kept_k[d, j] * strides[d]
        if d == last:
            out_index[n] = index
            out_value[n] = value
            n += 1
        else:
            d += 1
            pos[d] = 0
            prefix_gap[d] = gap
            prefix_value[d] = value
            prefix_index[d] = index
    # Relative values -> features: normalised by the sum over the whole grid (so every kept
    # feature equals its dense value), or scaled back to the raw Gaussian.
    scale = 1.0 / grid_sum if normalize else np.exp(-min_total)
    m = 0
    for j in range(n):
        value = out_value[j] * scale
        if value > 0.0:  # raw Gaussians of far-away states can underflow to 0
            out_index[m] = out_index[j]
            out_value[m] = value
            m += 1
    for j in range(obs.shape[0] - num_dims):
        b = obs[num_dims + j]
        if not np.isfinite(b):
            return -1
        if b != 0.0:
            out_index[m] = num_gaussians + j
            out_value[m] = b
            m += 1
    return m
