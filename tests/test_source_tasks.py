"""The clustered source task set C: drawn from the pool, distinct, deterministic, cached."""

import math
import warnings

import numpy as np
import pytest

from mediated_transfer.env import WorldConfig, sample_tasks
from mediated_transfer.env.paper import PaperWorld
from mediated_transfer.transfer import source_tasks
from mediated_transfer.transfer.source_tasks import (
    cluster_representatives,
    precompute_source_task_sets,
    sensor_vectors,
    source_task_set,
)

POOL = 300
WORLD = WorldConfig()


def coordinates(tasks):
    return np.array([t.coordinates for t in tasks])


def forbid(monkeypatch, name):
    def fail(*args, **kwargs):
        raise AssertionError(f"{name} must not be called")

    # The pool is the world's draw (env/door.py): the paper's world's sample_tasks.
    monkeypatch.setattr(PaperWorld if name == "sample_tasks" else source_tasks, name, fail)


def test_returns_n_distinct_tasks_of_the_pool():
    chosen = coordinates(source_task_set(20, WORLD, pool_size=POOL, seed=1))
    pool = coordinates(sample_tasks("source", POOL, np.random.default_rng(1), WORLD))
    assert chosen.shape == (20, 5)
    assert len({tuple(row) for row in chosen}) == 20
    assert all(np.any(np.all(pool == row, axis=1)) for row in chosen)


def test_same_seed_same_set_other_seed_other_set():
    a = coordinates(source_task_set(15, WORLD, pool_size=POOL, seed=4))
    b = coordinates(source_task_set(15, WORLD, pool_size=POOL, seed=4))
    c = coordinates(source_task_set(15, WORLD, pool_size=POOL, seed=5))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_zero_source_tasks_means_no_source_phase_and_no_work(monkeypatch):
    forbid(monkeypatch, "sample_tasks")
    assert source_task_set(0, WORLD, pool_size=POOL) == []


@pytest.mark.parametrize(
    "n_source, pool_size, seed, message",
    [
        (301, 300, 0, "n_source=301 exceeds pool_size=300"),
        (-1, 300, 0, "n_source must be an integer >= 0"),
        (2.5, 300, 0, "n_source must be an integer >= 0"),
        (5, 0, 0, "pool_size must be an integer >= 1"),
        (5, 300, -1, "seed must be an integer >= 0"),
    ],
)
def test_bad_input_fails_before_any_work(monkeypatch, n_source, pool_size, seed, message):
    forbid(monkeypatch, "sample_tasks")
    with pytest.raises(ValueError, match=message):
        source_task_set(n_source, WORLD, pool_size=pool_size, seed=seed)


def test_clustering_follows_cosine_similarity_and_keeps_the_most_central_task():
    # Two directions, each with tasks of very different lengths. Clustering by cosine groups
    # them by direction (k-means on raw vectors would group them by length); the kept task of
    # each group is the one pointing most nearly along the group's mean direction.
    def at(angle, length):
        return [length * math.cos(angle), length * math.sin(angle)]

    sensors = np.array(
        [at(-0.1, 1), at(0.0, 50), at(0.1, 3), at(1.47, 40), at(1.57, 2), at(1.67, 7)]
    )
    assert cluster_representatives(sensors, 2, seed=0).tolist() == [1, 4]


def test_every_cluster_yields_a_distinct_task_even_with_repeated_sensor_vectors():
    # 3 distinct vectors, each 4 times: k-means finds at most 3 non-empty clusters of 5.
    sensors = np.repeat(np.eye(3) + 0.1, 4, axis=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        chosen = cluster_representatives(sensors, 5, seed=0)
    assert len(set(chosen.tolist())) == 5
    # ... and still one from each distinct vector.
    assert {int(i) // 4 for i in chosen} == {0, 1, 2}


def test_cache_hit_returns_the_same_set_without_clustering(tmp_path, monkeypatch):
    first = source_task_set(12, WORLD, pool_size=POOL, seed=2, cache_dir=tmp_path)
    assert len(list(tmp_path.glob("*.npz"))) == 1
    forbid(monkeypatch, "cluster_representatives")
    forbid(monkeypatch, "sample_tasks")
    again = source_task_set(12, WORLD, pool_size=POOL, seed=2, cache_dir=tmp_path)
    assert again == first


def test_cache_key_covers_n_source_seed_pool_and_world(tmp_path):
    source_task_set(5, WORLD, pool_size=POOL, seed=0, cache_dir=tmp_path)
    source_task_set(6, WORLD, pool_size=POOL, seed=0, cache_dir=tmp_path)
    source_task_set(5, WORLD, pool_size=POOL, seed=1, cache_dir=tmp_path)
    source_task_set(5, WORLD, pool_size=POOL + 1, seed=0, cache_dir=tmp_path)
    source_task_set(5, WorldConfig(goal_radius=1.5), pool_size=POOL, seed=0, cache_dir=tmp_path)
    assert len(list(tmp_path.glob("*.npz"))) == 5
    assert not list(tmp_path.glob("*.tmp"))


def test_the_move_frame_shares_a_cached_set_and_keeps_older_files_valid(tmp_path):
    # Sampling and clustering read the world's sizes only: both frames share one set, and the
    # key of the default world is the one it had before the world gained move_frame.
    key = lambda world: source_tasks._cache_path(tmp_path, 50, world, 10_000, 0, source_tasks.ClusteringConfig())
    assert key(WORLD).name == "source_tasks_n50_589c123fa8fb1c7b.npz"
    assert key(WorldConfig(move_frame="tool")) == key(WORLD)
    assert key(WorldConfig(tool_hook_length=5.0)) != key(WORLD)


def test_a_cache_file_of_the_wrong_shape_is_recomputed(tmp_path):
    first = source_task_set(8, WORLD, pool_size=POOL, seed=3, cache_dir=tmp_path)
    (path,) = tmp_path.glob("*.npz")
    np.savez(path, coordinates=np.zeros((7, 5)))
    assert source_task_set(8, WORLD, pool_size=POOL, seed=3, cache_dir=tmp_path) == first


def test_precompute_warms_the_cache_for_a_sweep(tmp_path, monkeypatch):
    files = precompute_source_task_sets([0, 1, 10, 10], WORLD, pool_size=POOL, seed=0, cache_dir=tmp_path)
    assert sorted(files) == [1, 10] and all(path.is_file() for path in files.values())
    forbid(monkeypatch, "cluster_representatives")
    sets = {n: source_task_set(n, WORLD, pool_size=POOL, seed=0, cache_dir=tmp_path) for n in (1, 10)}
    assert [len(s) for s in sets.values()] == [1, 10]


def test_precompute_checks_every_size_before_working(tmp_path, monkeypatch):
    forbid(monkeypatch, "sample_tasks")
    with pytest.raises(ValueError, match="n_source=5000 exceeds pool_size=300"):
        precompute_source_task_sets([1, 5000], WORLD, pool_size=POOL, cache_dir=tmp_path)


def test_sensor_vectors_are_the_tasks_eq2_vectors():
    pool = sample_tasks("source", 5, np.random.default_rng(0), WORLD)
    np.testing.assert_array_equal(sensor_vectors(pool, WORLD), [t.sensor_vector(WORLD) for t in pool])


def test_a_read_only_cache_does_not_stop_a_run_that_can_do_without_it(tmp_path, monkeypatch):
    import errno

    def read_only(path, write):  # what writing into a read-only cache folder raises
        raise PermissionError(errno.EACCES, "Permission denied", str(path))

    monkeypatch.setattr(source_tasks, "atomic_write", read_only)
    tasks = source_tasks.source_task_set(5, pool_size=100, seed=3, cache_dir=tmp_path)
    assert tasks == source_tasks.source_task_set(5, pool_size=100, seed=3)
    assert not list(tmp_path.iterdir())
