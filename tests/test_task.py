"""Task instances c = (s, t): geometry, validation and the source/target samplers."""

import math

import numpy as np
import pytest

from mediated_transfer.env import M1, M2, M3, O, T, Task, WorldConfig, sample_task, sample_tasks

CONFIG = WorldConfig()


def test_picking_locations_follow_the_tool_frame():
    # Handle along the angle from the corner M2 to M1, hook a quarter turn counter-clockwise.
    task = Task((12.0, 0.0), (4.0, 3.0), math.pi / 2)
    locations = task.picking_locations(CONFIG)
    np.testing.assert_allclose(locations[M2], [4.0, 3.0])
    np.testing.assert_allclose(locations[M1], [4.0, 3.0 + CONFIG.tool_handle_length], atol=1e-12)
    np.testing.assert_allclose(locations[M3], [4.0 - CONFIG.tool_hook_length, 3.0], atol=1e-12)
    np.testing.assert_allclose(locations[T], [12.0, 0.0])
    np.testing.assert_allclose(locations[O], [0.0, 0.0])


def test_sensor_vector_by_hand():
    task = Task((12.0, 0.0), (4.0, 3.0), 0.0)  # M1 (11, 3), M2 (4, 3), M3 (4, 6.5)
    expected = [
        math.sqrt(1 + 9), math.sqrt(64 + 9), math.sqrt(64 + 6.5**2),
        math.sqrt(121 + 9), 5.0, math.sqrt(16 + 6.5**2),
        0, 0, 0, 0, 1,
    ]
    np.testing.assert_allclose(task.sensor_vector(CONFIG), expected, rtol=1e-12)


def test_coordinates_round_trip_and_wrong_length():
    task = Task((1.0, 2.0), (3.0, 4.0), 0.5)
    assert Task.from_coordinates(task.coordinates) == task
    with pytest.raises(ValueError, match="5 task-space coordinates"):
        Task.from_coordinates([1.0, 2.0, 3.0])


@pytest.mark.parametrize(
    "task, problem",
    [
        (Task((4.0, 0.5), (4.0, 0.0), 0.0), "overlap"),  # target lies on the handle
        (Task((17.5, 0.0), (0.0, 0.0), 0.0), "target centre lies outside the world"),
        (Task((12.0, 0.0), (-15.0, 0.0), math.pi), "tool lies outside the world"),
        (Task((float("nan"), 0.0), (0.0, 0.0), 0.0), "finite"),
    ],
)
def test_invalid_tasks_are_named(task, problem):
    assert any(problem in p for p in task.problems(CONFIG))
    with pytest.raises(ValueError, match=problem):
        task.validate(CONFIG)


def _tool_radii(task):
    return np.linalg.norm(task.picking_locations(CONFIG)[:3], axis=1)


def test_source_tasks_have_target_and_tool_in_reach():
    rng = np.random.default_rng(0)
    for task in sample_tasks("source", 200, rng, CONFIG):
        assert not task.problems(CONFIG)
        r = task.target_distance
        assert CONFIG.goal_radius <= r <= CONFIG.interaction_radius - CONFIG.target_radius
        assert np.all(_tool_radii(task) <= CONFIG.interaction_radius)


def test_target_tasks_put_the_target_out_of_reach_in_the_annulus():
    rng = np.random.default_rng(0)
    for task in sample_tasks("target", 200, rng, CONFIG):
        assert not task.problems(CONFIG)
        assert CONFIG.mediated_min_distance <= task.target_distance <= CONFIG.mediated_max_distance
        assert np.all(_tool_radii(task) <= CONFIG.interaction_radius)


def test_sampling_is_seeded():
    a = sample_tasks("target", 5, np.random.default_rng(3), CONFIG)
    b = sample_tasks("target", 5, np.random.default_rng(3), CONFIG)
    c = sample_tasks("target", 5, np.random.default_rng(4), CONFIG)
    assert a == b
    assert a != c


def test_unknown_scenario_lists_the_allowed_ones():
    with pytest.raises(ValueError, match="source, target"):
        sample_task("mediated", np.random.default_rng(0), CONFIG)
