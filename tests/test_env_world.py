"""The pymunk world: driven bodies move exactly, free ones react, and the fast Chipmunk calls of
the per-step path leave pymunk's public view of the bodies consistent."""

import math

import numpy as np
import pymunk
import pytest

from mediated_transfer.env import M1, M2, M3, Task, WorldConfig
from mediated_transfer.env.world import World

CONFIG = WorldConfig()


def world_at(task):
    world = World(CONFIG)
    world.place(task)
    return world


def assert_public_view_matches(world):
    for body in (world.target, world.tool):
        assert body.body_type == pymunk.Body.DYNAMIC
    assert world.tool.position == pytest.approx((world.tool_x, world.tool_y), abs=1e-12)
    assert world.tool.angle == pytest.approx(world.tool_angle, abs=1e-12)
    assert world.target.position == pytest.approx((world.target_x, world.target_y), abs=1e-12)
    # The true centre of gravity of the L is back after a turn moved it to the pivot.
    lh, lk = CONFIG.tool_handle_length, CONFIG.tool_hook_length
    cog = (lh * lh / 2 / (lh + lk), lk * lk / 2 / (lh + lk))
    assert tuple(world.tool.center_of_gravity) == pytest.approx(cog)
    assert world.tool.mass == pytest.approx(CONFIG.tool_mass)


def test_a_driven_translation_is_exact_and_leaves_the_tool_at_rest():
    world = world_at(Task((-8.0, 0.0), (2.0, 1.0), 0.3))
    world.translate_tool(0.6, -0.8)
    assert (world.tool_x, world.tool_y) == pytest.approx((2.6, 0.2), abs=1e-9)
    assert world.tool_angle == pytest.approx(0.3, abs=1e-12)
    assert tuple(world.tool.velocity) == (0.0, 0.0) and world.tool.angular_velocity == 0.0
    assert world.physics_steps == CONFIG.substeps
    assert_public_view_matches(world)


@pytest.mark.parametrize("pivot", [M1, M2, M3])
def test_a_driven_turn_keeps_its_pivot_fixed(pivot):
    world = world_at(Task((-8.0, 0.0), (2.0, 1.0), 0.3))
    before = world.tool.local_to_world(world.tool_frame_locations[pivot])
    world.rotate_tool(pivot, -math.pi / 4)
    after = world.tool.local_to_world(world.tool_frame_locations[pivot])
    assert tuple(after) == pytest.approx(tuple(before), abs=1e-9)
    assert world.tool_angle == pytest.approx(0.3 - math.pi / 4, abs=1e-12)
    assert_public_view_matches(world)


def test_a_pushed_object_moves_and_then_comes_to_rest():
    world = world_at(Task((1.5, 0.0), (0.0, -3.0), math.pi / 2))  # handle on the y axis
    world.translate_tool(1.0, 0.0)  # the handle runs into the target
    assert world.target_x > 2.1  # pushed to the handle (Chipmunk allows 0.1 overlap)
    assert world.target.velocity.x > 0.0  # still coasting after the step
    assert not world.at_rest
    for _ in range(10):
        world.idle()
    assert world.at_rest and tuple(world.target.velocity) == (0.0, 0.0)
    steps = world.physics_steps
    world.idle()  # nothing moves: no physics
    assert world.physics_steps == steps


def test_the_wall_holds_a_target_squeezed_by_the_tool():
    # The driven tool is kinematic and does not collide with the wall: pressing the target
    # against the wall squeezes it in, but never through, and it comes back out.
    world = world_at(Task((15.5, 0.0), (14.0, -3.0), math.pi / 2))  # handle at x = 14
    for _ in range(3):
        world.translate_tool(1.0, 0.0)  # handle's outer face at 17.25: no room for the target
    assert math.hypot(world.target_x, world.target_y) < CONFIG.world_radius + CONFIG.wall_thickness / 2
    world.translate_tool(-2.0, 0.0)
    for _ in range(5):
        world.idle()
    radius = math.hypot(world.target_x, world.target_y)
    assert radius <= CONFIG.world_radius - CONFIG.target_radius + 0.1
    assert_public_view_matches(world)


def test_the_wall_keeps_its_inner_face_at_world_radius():
    world = World(CONFIG)
    walls = [s for s in world.space.shapes if s.body is world.space.static_body]
    assert len(walls) == CONFIG.wall_segments
    for segment in walls:
        a, b = np.array(segment.a), np.array(segment.b)
        midpoint_radius = np.linalg.norm((a + b) / 2)
        assert midpoint_radius - segment.radius == pytest.approx(CONFIG.world_radius)


class _PublicStepWorld(World):
    """The world stepped through pymunk's public ``Space.step``, as before the direct calls."""

    def _simulate(self) -> None:
        for _ in range(self._substeps):
            self.space.step(self._dt)
        self.physics_steps += self._substeps


def test_direct_chipmunk_steps_match_space_step_exactly():
    # Pushes, hook drags and coasting: every pose bit for bit as with pymunk's own step.
    worlds = [World(CONFIG), _PublicStepWorld(CONFIG)]
    poses = [[], []]
    for world, trace in zip(worlds, poses):
        for task in (Task((1.5, 0.0), (0.0, -3.0), math.pi / 2), Task((6.0, 2.0), (1.0, 0.0), 0.2)):
            world.place(task)
            for _ in range(4):
                world.translate_tool(1.0, 0.0)
                world.rotate_tool(M3, math.pi / 4)
                world.translate_tool(-0.5, 0.5)
                world.idle()
                trace.append((world.target_x, world.target_y, world.tool_x, world.tool_y,
                              world.tool_angle, world.at_rest))
    assert poses[0] == poses[1]
    assert poses[0][0][0] != 1.5  # the target was pushed
    assert worlds[0].physics_steps == worlds[1].physics_steps


def test_the_mediators_shape_is_config_and_the_paper_l_is_unchanged():
    import math

    from mediated_transfer.env import WorldConfig, tool_picking_locations

    l_shape = tool_picking_locations((1.0, 2.0), 0.3, WorldConfig())
    c, s = math.cos(0.3), math.sin(0.3)
    assert l_shape[2].tolist() == [1.0 - 3.5 * s, 2.0 + 3.5 * c]  # exactly as before the key existed
    stick = tool_picking_locations((0.0, 0.0), 0.0, WorldConfig(tool_hook_angle=180.0))
    assert stick[0].tolist() == [7.0, 0.0] and stick[2][0] == -3.5 and abs(stick[2][1]) < 1e-12
    with pytest.raises(ValueError, match="env.tool_hook_angle must lie in"):
        WorldConfig(tool_hook_angle=200.0)
