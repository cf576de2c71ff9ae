"""The source task set C (Sec. IV-A): N_source tasks that cover the sensor space evenly.

Following the paper: draw ``pool_size`` (10^4) random source tasks, cluster them on their
sensor vectors s into N_source clusters, and keep from each cluster the task whose s is most
similar to the cluster's centre.

Clustering is made consistent with the cosine similarity of eq. (3), which also drives the
scaffolded strategy: every s is scaled to unit length, so the squared Euclidean distance
k-means minimises is 2 - 2 cos(u, v). Within a cluster, the task closest to the centre c is
also the one with the largest cosine similarity to c (|u - c|^2 = 1 - 2 u.c + |c|^2, with |c|
fixed). s is the full 11-dim sensor vector of eq. (2) at an episode's start, one-hot of O
included: that is what the paper calls the sensor vector; the constant one-hot adds the same
component to every s, which only damps the cosine contrast of the 6 distances.

k-means (scikit-learn's Lloyd, k-means++ start, one initialisation, single-threaded so the
floating-point sums, and so the result, do not depend on the machine) is deterministic for a
seed. N_source = 5000 on 10^4 tasks takes a few seconds; sets are still cached on disk (.npz of
the task coordinates t, keyed by everything they depend on) so that a sweep computes each set
once: call ``precompute_source_task_sets`` before the sweep starts.

The world decides what a task is and what its sensor vector holds (env/door.py): the pool is
the world's ``sample_tasks("source", ...)``, the clustering reads its ``task_sensors(tasks)``, and a
cached set is read back through its ``task_from_coordinates``. The paper's world gives the
vectors of eq. (2) and tasks of 5 coordinates; a world with another sensor, a second tool or a
second target gives its own.
"""

from __future__ import annotations

import hashlib
import json
import logging
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from ..atomic import atomic_write
from ..env.config import WorldConfig
from ..env.door import PAPER_WORLD, as_world
from ..env.task import Task, sensor_vectors

log = logging.getLogger(__name__)

#: Bump when the selection procedure changes, so old cache files are no longer used.
METHOD_VERSION = 1
#: World fields a source task set does not depend on (sampling and clustering read the sizes
#: only), left out of the cache key: the move frame's readings share one set, and the files
#: cached before the field existed stay valid.
NOT_IN_CACHE_KEY = ("move_frame",)
KEYS_ADDED_LATER = {"tool_hook_angle": 90.0}
"""World keys added after sets were cached, with the value every earlier set had: at that value
a key stays out of the cache key, so the files cached before it stay valid."""


@dataclass(frozen=True)
class ClusteringConfig:
    max_iter: int = 300
    """k-means iterations at most (scikit-learn's default; 5000 clusters converge in < 10)."""
    tol: float = 1e-4
    """k-means convergence tolerance on the centre shift (scikit-learn's default)."""

    def __post_init__(self) -> None:
        if not self.max_iter >= 1:
            raise ValueError(f"clustering.max_iter must be >= 1, got {self.max_iter!r}")
        if not self.tol >= 0:
            raise ValueError(f"clustering.tol must be >= 0, got {self.tol!r}")


def task_sensors(world, tasks: Sequence) -> np.ndarray:
    """The sensor vectors of ``tasks`` at their start, one row each, as ``world`` (a world or
    its config, env/door.py's ``as_world``) senses them (its ``task_sensors``; a world without
    one: the paper's eq. 2)."""
    world = as_world(world)
    own = getattr(world, "task_sensors", None)
    return np.asarray(own(list(tasks)) if own is not None else sensor_vectors(tasks, world.config), dtype=float)


def cluster_representatives(
    sensors: np.ndarray,
    n_clusters: int,
    seed: int = 0,
    clustering: ClusteringConfig = ClusteringConfig(),
) -> np.ndarray:
    """Row indices of ``n_clusters`` distinct rows, one per k-means cluster of the unit-scaled
    rows: the row most cosine-similar to its cluster's centre. Sorted ascending.

    A cluster left empty (possible only with repeated rows) takes the not yet chosen row
    closest to its centre, so the result always has ``n_clusters`` distinct indices.
    """
    from sklearn.cluster import KMeans
    from threadpoolctl import threadpool_limits

    sensors = np.asarray(sensors, dtype=float)
    n = sensors.shape[0]
    if not 1 <= n_clusters <= n:
        raise ValueError(f"n_clusters must lie in [1, {n}] (the number of rows), got {n_clusters}")
    norms = np.linalg.norm(sensors, axis=1)
    if not np.all(np.isfinite(norms)) or np.any(norms == 0):
        raise ValueError("sensor vectors must be finite and non-zero to be clustered by cosine")
    unit = sensors / norms[:, None]
    kmeans = KMeans(
        n_clusters=n_clusters,
        n_init=1,
        max_iter=clustering.max_iter,
        tol=clustering.tol,
        random_state=seed,
    )
    with threadpool_limits(limits=1):
        labels = kmeans.fit_predict(unit)
    centres = kmeans.cluster_centers_
    distance = np.linalg.norm(unit - centres[labels], axis=1)
    # Sort by (cluster, distance to its centre): the first row of each cluster is its
    # representative (ties: lower row index, the sort is stable).
    order = np.lexsort((distance, labels))
    first = np.ones(n, dtype=bool)
    first[1:] = labels[order][1:] != labels[order][:-1]
    chosen = np.full(n_clusters, -1)
    chosen[labels[order][first]] = order[first]
    taken = np.zeros(n, dtype=bool)
    taken[chosen[chosen >= 0]] = True
    for cluster in np.flatnonzero(chosen < 0):
        d = np.linalg.norm(unit - centres[cluster], axis=1)
        d[taken] = np.inf
        chosen[cluster] = int(np.argmin(d))
        taken[chosen[cluster]] = True
    return np.sort(chosen)


def source_task_set(
    n_source: int,
    world: WorldConfig = WorldConfig(),
    pool_size: int = 10_000,
    seed: int = 0,
    cache_dir: str | Path | None = None,
    clustering: ClusteringConfig = ClusteringConfig(),
) -> list[Task]:
    """The source task set C: ``n_source`` clustered source tasks (empty for n_source = 0).

    Deterministic for (n_source, world, pool_size, seed, clustering). With ``cache_dir`` the set
    is read from / written to ``cache_dir``; without it, it is computed every call.
    """
    _check(n_source, pool_size, seed)
    if n_source == 0:
        return []
    world = as_world(world)
    path = _cache_path(cache_dir, n_source, world, pool_size, seed, clustering)
    if path is not None:
        cached = _read(path, n_source, world)
        if cached is not None:
            return cached
    pool = world.sample_tasks("source", pool_size, np.random.default_rng(seed))
    return _select_and_store(pool, task_sensors(world, pool), n_source, seed, clustering, path)


def precompute_source_task_sets(
    n_sources: Iterable[int],
    world: WorldConfig = WorldConfig(),
    pool_size: int = 10_000,
    seed: int = 0,
    *,
    cache_dir: str | Path,
    clustering: ClusteringConfig = ClusteringConfig(),
) -> dict[int, Path]:
    """Warm the cache for every N_source of a sweep (one shared pool); returns the files.

    Call it once before parallel workers start, so none of them clusters; n_source = 0 needs
    no file and is skipped.
    """
    n_sources = list(n_sources)
    for n in n_sources:
        _check(n, pool_size, seed)
    n_sources = sorted({int(n) for n in n_sources})
    if cache_dir is None:
        raise ValueError("precompute_source_task_sets needs a cache_dir to write to")
    files: dict[int, Path] = {}
    pool = sensors = None
    world = as_world(world)
    for n in n_sources:
        if n == 0:
            continue
        path = _cache_path(cache_dir, n, world, pool_size, seed, clustering)
        files[n] = path
        if _read(path, n, world) is not None:
            continue
        if pool is None:
            pool = world.sample_tasks("source", pool_size, np.random.default_rng(seed))
            sensors = task_sensors(world, pool)
        _select_and_store(pool, sensors, n, seed, clustering, path)
    return files


def _check(n_source, pool_size, seed=0) -> None:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {seed!r}")
    if isinstance(pool_size, bool) or not isinstance(pool_size, (int, np.integer)) or pool_size < 1:
        raise ValueError(f"pool_size must be an integer >= 1, got {pool_size!r}")
    if isinstance(n_source, bool) or not isinstance(n_source, (int, np.integer)) or n_source < 0:
        raise ValueError(f"n_source must be an integer >= 0, got {n_source!r}")
    if n_source > pool_size:
        raise ValueError(
            f"n_source={n_source} exceeds pool_size={pool_size}: each source task is one of "
            f"the pool's random tasks, so n_source must be <= pool_size"
        )


def _select_and_store(pool, sensors, n_source, seed, clustering, path) -> list[Task]:
    start = time.perf_counter()
    chosen = cluster_representatives(sensors, n_source, seed, clustering)
    log.info(
        "source task set: %d clusters of %d tasks in %.2f s", n_source, len(pool),
        time.perf_counter() - start,
    )
    tasks = [pool[i] for i in chosen]
    if path is not None:
        # Atomic: parallel workers may write the same set at once; a reader never sees half.
        coordinates = np.array([t.coordinates for t in tasks])
        try:
            atomic_write(path, lambda handle: np.savez(handle, coordinates=coordinates, pool_indices=chosen))
        except OSError as error:  # e.g. a read-only cache: the run needs the set, not the file
            log.warning("source task set not cached (%s: %s); it is recomputed when needed",
                        path.parent, error.strerror or error)
    return tasks


def _cache_path(cache_dir, n_source, world, pool_size, seed, clustering) -> Path | None:
    if cache_dir is None:
        return None
    world = as_world(world)
    config = world.config
    values = config.to_dict() if hasattr(config, "to_dict") else asdict(config)
    fields = {
        "method": METHOD_VERSION,
        "n_source": int(n_source),
        "pool_size": int(pool_size),
        "seed": int(seed),
        "world": {k: v for k, v in values.items()
                  if k not in NOT_IN_CACHE_KEY and KEYS_ADDED_LATER.get(k, object()) != v},
        "clustering": asdict(clustering),
    }
    cls = type(world)
    if f"{cls.__module__}.{cls.__qualname__}" != PAPER_WORLD:
        # Another world may sample or sense the same config's tasks otherwise; the paper's
        # keeps the key its files were cached under.
        fields["world_class"] = f"{cls.__module__}.{cls.__qualname__}"
    key = json.dumps(fields, sort_keys=True)
    digest = hashlib.sha256(key.encode()).hexdigest()[:16]
    return Path(cache_dir) / f"source_tasks_n{n_source}_{digest}.npz"


def _read(path: Path, n_source: int, world) -> list | None:
    """The cached set, or None when the file is missing or not a valid set of n_source tasks
    of ``world`` (its ``task_from_coordinates``)."""
    if not path.is_file():
        return None
    try:
        with np.load(path) as data:
            coordinates = np.array(data["coordinates"], dtype=float)
    except (OSError, KeyError, ValueError) as error:
        log.warning("ignoring unreadable source task cache %s: %s", path, error)
        return None
    if coordinates.ndim != 2 or coordinates.shape[0] != n_source or not np.all(np.isfinite(coordinates)):
        log.warning(
            "ignoring source task cache %s: coordinates of shape %s, expected (%d, task coordinates)",
            path, coordinates.shape, n_source,
        )
        return None
    decode = getattr(world, "task_from_coordinates", Task.from_coordinates)
    try:
        return [decode(t) for t in coordinates]
    except ValueError as error:  # e.g. a file of another world's tasks
        log.warning("ignoring source task cache %s: %s", path, error)
        return None


