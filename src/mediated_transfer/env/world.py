"""The pymunk simulation of the paper's world: a disc target, an L-shaped tool, a circular wall.

The agent applies no forces. The object it holds is switched to a kinematic body for one step
and driven along the action's exact motion; with its infinite mass it pushes the other object,
and with the hook drags it, through real contacts. Free objects are dynamic bodies: no gravity,
no friction, damped velocities. Task semantics (range, picking, refusals) live in the
environment; this module only moves bodies.
"""

from __future__ import annotations

import math

import pymunk

# Speed: in this three-body world pymunk's Python property wrappers cost more than the physics
# (switching a body's type through ``body.body_type`` takes ~5x a ``space.step``). The per-step
# path therefore calls the Chipmunk functions those properties wrap, on the body's Chipmunk
# handle; that is pymunk 7's internal layout (pinned <8), and tests/test_env_world.py checks
# the result against the public properties. Everything outside the per-step path is public API.
# The physics substeps call ``cpSpaceStep`` itself: ``Space.step`` costs ~2.4x it, for a mass
# check of newly added bodies and for deferring adds, removals and post-step callbacks made from
# collision callbacks; this world registers no callbacks and its masses are validated config.
from pymunk._chipmunk_cffi import lib as _cp

from .config import WorldConfig
from .task import Task

_KINEMATIC = pymunk.Body.KINEMATIC
_DYNAMIC = pymunk.Body.DYNAMIC
_set_type = _cp.cpBodySetType
_set_velocity = _cp.cpBodySetVelocity
_set_angular_velocity = _cp.cpBodySetAngularVelocity
_set_position = _cp.cpBodySetPosition
_set_center_of_gravity = _cp.cpBodySetCenterOfGravity
_get_position = _cp.cpBodyGetPosition
_get_velocity = _cp.cpBodyGetVelocity
_get_angle = _cp.cpBodyGetAngle
_get_angular_velocity = _cp.cpBodyGetAngularVelocity
_space_step = _cp.cpSpaceStep


class World:
    """Bodies, shapes, the wall and the physics step, with a cache of the current poses.

    The tool's body frame has its origin at the L's corner M2, the handle along +x (to M1) and
    the hook along +y (to M3), so the body's position and angle are the task-space coordinates.
    """

    def __init__(self, config: WorldConfig) -> None:
        self.config = config
        self.space = pymunk.Space()
        # Chipmunk's damping is the fraction of velocity kept per simulated second: our meaning.
        self.space.damping = config.damping
        self._dt = config.step_duration / config.substeps
        self._substeps = config.substeps
        self._per_second = 1.0 / config.step_duration  # a step's displacement -> a velocity
        self._rest_speed = config.rest_speed
        self._add_wall()

        self.target = pymunk.Body()
        disc = pymunk.Circle(self.target, config.target_radius)
        disc.mass = config.target_mass
        self.tool = pymunk.Body()
        half = config.tool_width / 2
        total = sum(length for _, _, length in config.tool_segments)
        arms = []
        for start, end, length in config.tool_segments:  # the L: its handle, then its hook
            arm = pymunk.Segment(self.tool, start, end, half)
            # Masses on the shapes, not the body: switching back to DYNAMIC recomputes the
            # body's mass, moment and centre of gravity from them.
            arm.mass = config.tool_mass * length / total
            arms.append(arm)
        for shape in (disc, *arms):
            shape.friction = 0.0
            shape.elasticity = 0.0
        self._objects = (self.target, disc, self.tool, *arms)
        self.space.add(*self._objects)
        self._target_cp, self._tool_cp = self.target._body, self.tool._body
        self._space_cp = self.space._space
        #: M1, M2, M3 in the tool's body frame (rotation pivots).
        self.tool_frame_locations = config.tool_points

        self.physics_steps = 0
        """Physics substeps (``cpSpaceStep`` calls) made so far (the benchmark counts them)."""
        self.at_rest = True
        """Nothing moves: a step that drives nothing has nothing to simulate."""
        self.target_x = self.target_y = 0.0
        self.tool_x = self.tool_y = self.tool_angle = 0.0

    def _add_wall(self) -> None:
        c = self.config
        n, half = c.wall_segments, c.wall_thickness / 2
        # Chords of a polygon sag inwards; pushing the vertices out keeps every point of the
        # wall's inner face at or beyond world_radius.
        r = (c.world_radius + half) / math.cos(math.pi / n)
        corners = [
            (r * math.cos(2 * math.pi * i / n), r * math.sin(2 * math.pi * i / n)) for i in range(n)
        ]
        body = self.space.static_body
        for i in range(n):
            segment = pymunk.Segment(body, corners[i], corners[(i + 1) % n], half)
            segment.friction = 0.0
            segment.elasticity = 0.0
            self.space.add(segment)

    # --- episode start ------------------------------------------------------------------------
    def place(self, task: Task) -> None:
        """Put the objects at the task's poses, at rest, with no contact history."""
        # Removing and re-adding the objects drops Chipmunk's cached contacts (it warm-starts
        # from them). It does not make an episode independent of the ones before it: replayed
        # alone in a fresh environment, about 3 % of a learner's episodes end differently
        # (measured with the env bench's recordings; some Chipmunk state, e.g. its spatial
        # index, outlives the re-add). A run is still deterministic: same seed, same sequence
        # of episodes, same rollout. A fresh Space per episode would fix it at a cost.
        self.space.remove(*self._objects)
        for body, position, angle in (
            (self.target, task.target_position, 0.0),
            (self.tool, task.tool_position, task.tool_angle),
        ):
            body.body_type = _DYNAMIC
            body.velocity = (0.0, 0.0)
            body.angular_velocity = 0.0
            body.angle = angle  # first: setting the angle turns the body about its cog
            body.position = position
        self.space.add(*self._objects)
        self.at_rest = True
        self._read_poses()

    # --- one environment step -----------------------------------------------------------------
    def idle(self) -> None:
        """A step that drives nothing: free objects coast until they come to rest."""
        if self.at_rest:
            return  # nothing would move
        self._simulate()
        target, tool, rest = self._target_cp, self._tool_cp, self._rest_speed
        vt, vm = _get_velocity(target), _get_velocity(tool)
        if (
            math.hypot(vt.x, vt.y) < rest
            and math.hypot(vm.x, vm.y) < rest
            and abs(_get_angular_velocity(tool)) < rest
        ):
            _set_velocity(target, (0.0, 0.0))
            _set_velocity(tool, (0.0, 0.0))
            _set_angular_velocity(tool, 0.0)
            self.at_rest = True
        self._read_poses()

    def translate_target(self, dx: float, dy: float) -> None:
        """Move the target by (dx, dy) over one step, pushing the tool."""
        self._translate(self._target_cp, dx, dy)

    def translate_tool(self, dx: float, dy: float) -> None:
        """Move the tool by (dx, dy) over one step, pushing (or with the hook dragging) the target."""
        self._translate(self._tool_cp, dx, dy)

    def _translate(self, body, dx: float, dy: float) -> None:
        _set_type(body, _KINEMATIC)  # infinite mass for the step; also zeroes its velocity
        _set_velocity(body, (dx * self._per_second, dy * self._per_second))
        self._simulate()
        _set_velocity(body, (0.0, 0.0))
        _set_type(body, _DYNAMIC)  # recomputes mass, moment and centre of gravity
        self.at_rest = False  # the other object may have been pushed
        self._read_poses()

    def rotate_tool(self, pivot: int, angle: float) -> None:
        """Turn the tool by ``angle`` around its picking location ``pivot`` (M1, M2 or M3)."""
        tool = self._tool_cp
        _set_type(tool, _KINEMATIC)
        # A body turns about its centre of gravity: put that at the pivot for the step, then
        # re-set the position so the pose itself does not jump. Going back to DYNAMIC restores
        # the true centre of gravity (and keeps the pose).
        _set_center_of_gravity(tool, self.tool_frame_locations[pivot])
        _set_position(tool, (self.tool_x, self.tool_y))
        _set_angular_velocity(tool, angle * self._per_second)
        self._simulate()
        _set_angular_velocity(tool, 0.0)
        _set_type(tool, _DYNAMIC)
        self.at_rest = False
        self._read_poses()

    def _simulate(self) -> None:
        step, space, dt = _space_step, self._space_cp, self._dt
        for _ in range(self._substeps):
            step(space, dt)
        self.physics_steps += self._substeps

    def _read_poses(self) -> None:
        p = _get_position(self._target_cp)
        self.target_x, self.target_y = p.x, p.y
        p = _get_position(self._tool_cp)
        self.tool_x, self.tool_y = p.x, p.y
        self.tool_angle = _get_angle(self._tool_cp)
