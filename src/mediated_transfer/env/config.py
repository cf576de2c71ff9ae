"""Every geometric and physical constant of the simulated world, in one place.

The paper fixes the interaction range (radius 10), the move length (one unit), the rotation step
(pi/4), the episode length (100), the reward (10) and the action noise (0.1). Everything else it
leaves open; the defaults below are this project's choices (the option ``env=default``, see
config/schema.py), and the tests check that both source and target tasks stay solvable by a scripted policy with them.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields


MAX_SUBSTEPS = 1000
"""Most physics substeps per environment step: 100x the default's cost per step already."""
MAX_SCALE = 1e6
"""Lengths, masses, times and speeds lie within [1/MAX_SCALE, MAX_SCALE]: the defaults are near
1, and pymunk's float64 contacts overflow to non-finite positions with masses of 1e308."""
MAX_REWARD = 1e6
"""Largest success reward (the paper: 10); sums of larger ones may overflow to inf."""
MAX_WALL_SEGMENTS = 10_000
"""Most wall segments: a finer polygon than this changes nothing but the cost of collisions."""
MOVE_FRAMES = ("radial", "tool")
"""The readings of the paper's "non-static coordinate system" of moves (``move_frame``)."""


@dataclass(frozen=True)
class WorldConfig:
    # --- fixed by the paper -------------------------------------------------------------
    interaction_radius: float = 10.0
    """Agent's reach around the origin O: only picking locations inside it can be picked."""
    move_distance: float = 1.0
    """Distance the active picking location moves per move action."""
    rotation_angle: float = math.pi / 4
    """Tool rotation per rotate action, around the active picking location."""
    max_episode_steps: int = 100
    """Episode truncation."""
    success_reward: float = 10.0
    """Reward on success (the episode then terminates); 0 otherwise."""
    action_noise: float = 0.1
    """Probability that a uniformly random action replaces the chosen one (also in evaluation)."""

    # --- chosen by this project -----------------------------------------------------------
    goal_radius: float = 2.0
    """Success when the target's centre lies within this distance of O."""
    world_radius: float = 18.0
    """A circular wall at this radius keeps objects (and so the observation) bounded."""
    target_radius: float = 1.0
    """Radius of the disc-shaped target object."""
    tool_handle_length: float = 7.0
    """Length of the L's long arm, from the corner M2 to the handle end M1."""
    tool_hook_length: float = 3.5
    """Length of the L's short arm, from the corner M2 to the hook end M3."""
    tool_hook_angle: float = 90.0
    """Angle in degrees from the handle to the hook, in (0, 180]: the mediator's shape. 90 is
    the paper's L; 180 a straight stick (M1 and M3 its ends, M2 between them); between, a hook
    opening outward (conf/env/ and docs/extending.md: a world variant is config)."""
    tool_width: float = 0.5
    """Thickness of both arms of the tool."""
    mediated_min_distance: float = 10.5
    """Target tasks place the target's centre at least this far from O (out of reach).
    Calibrated: with [11.5, 13.5] linear Q(lambda) without transfer ended at <R> ~ 5 after 500k
    steps; [10.5, 12.5] keeps the target unreachable and needs the hook, with a shorter pull."""
    mediated_max_distance: float = 12.5
    """... and at most this far."""
    step_duration: float = 1.0
    """Simulated seconds per environment step (a move covers move_distance in this time)."""
    substeps: int = 10
    """pymunk ``space.step`` calls per environment step (keeps a pi/4 sweep from tunnelling)."""
    damping: float = 0.05
    """Fraction of linear and angular velocity kept after one simulated second (no friction)."""
    target_mass: float = 1.0
    """Mass of the target disc (only matters when the tool pushes it)."""
    tool_mass: float = 1.0
    """Mass of the tool, spread over its two arms by length (only matters when pushed)."""
    wall_segments: int = 64
    """Straight static segments approximating the circular wall."""
    wall_thickness: float = 2.0
    """Thickness of the wall; its inner face lies at world_radius (thick so nothing tunnels)."""
    rest_speed: float = 1e-3
    """A free object slower than this (units/s, rad/s) is set to rest, as Chipmunk's sleeping
    would; while everything rests, steps that drive nothing skip the physics."""
    move_frame: str = "radial"
    """The frame of the four move actions (5-8), the paper's "non-static coordinate system"
    (its Fig. 1b), which it draws but does not define. ``radial``: the frame attached at the
    active picking location P and oriented by O: 5/6 move P radially out/in (along +-P/|P|),
    7/8 tangentially counter-clockwise/clockwise around O. ``tool``: when a tool location
    (M1, M2 or M3) is active, the frame attached to the tool itself, whichever of the three is
    held: 5/6 move the tool along its handle, towards M1 / away from it (+-(M1 - M2)/|M1 - M2|),
    7/8 along its hook, towards M3 / away from it (+-(M3 - M2)/|M3 - M2|, the handle's
    direction turned by +pi/2); holding the target T, whose disc has no orientation, keeps the
    radial frame. Both frames map 5 to a direction and 7 to that direction turned by +pi/2."""

    def __post_init__(self) -> None:
        # Python callers and mappings are not typed by Hydra: a number where a number belongs,
        # finite (inf or nan lengths would reach the physics as nan positions).
        for f in fields(self):
            value = getattr(self, f.name)
            if f.type == "int" and (isinstance(value, bool) or not isinstance(value, int)):
                raise ValueError(f"env.{f.name} must be an integer, got {value!r}")
            if f.type == "float" and (isinstance(value, bool) or not isinstance(value, (int, float))
                                      or not math.isfinite(value)):
                raise ValueError(f"env.{f.name} must be a finite number, got {value!r}")
        if self.move_frame not in MOVE_FRAMES:
            raise ValueError(f"env.move_frame must be one of {', '.join(MOVE_FRAMES)}, got {self.move_frame!r}")
        positive = [f.name for f in fields(self) if f.type in ("int", "float")
                    and f.name not in ("action_noise", "damping")]
        for name in positive:
            if not getattr(self, name) > 0:
                raise ValueError(f"env.{name} must be > 0, got {getattr(self, name)!r}")
        for f in fields(self):
            if f.type == "float" and f.name in positive and not 1 / MAX_SCALE <= getattr(self, f.name) <= MAX_SCALE:
                raise ValueError(f"env.{f.name} must lie in [{1 / MAX_SCALE:g}, {MAX_SCALE:g}] (beyond, "
                                 f"the physics overflows or stalls), got {getattr(self, f.name)!r}")
        if not 0.0 <= self.action_noise <= 1.0:
            raise ValueError(f"env.action_noise must lie in [0, 1], got {self.action_noise!r}")
        if not 3 <= self.wall_segments <= MAX_WALL_SEGMENTS:
            raise ValueError(f"env.wall_segments must lie in [3, {MAX_WALL_SEGMENTS}], got {self.wall_segments!r}")
        if not self.substeps <= MAX_SUBSTEPS:
            raise ValueError(f"env.substeps must lie in [1, {MAX_SUBSTEPS}] (each is a physics step "
                             f"of every environment step), got {self.substeps!r}")
        if not self.rotation_angle <= math.pi:
            raise ValueError(f"env.rotation_angle must lie in (0, pi], got {self.rotation_angle!r}")
        if not 0.0 < self.tool_hook_angle <= 180.0:
            raise ValueError(f"env.tool_hook_angle must lie in (0, 180] degrees, got {self.tool_hook_angle!r}")
        if not 0.0 < self.damping <= 1.0:
            raise ValueError(f"env.damping must lie in (0, 1], got {self.damping!r}")
        if not self.success_reward <= MAX_REWARD:
            raise ValueError(f"env.success_reward must lie in (0, {MAX_REWARD:g}] (reward losses "
                             f"sum it over evaluation points), got {self.success_reward!r}")
        if not self.goal_radius < self.interaction_radius:
            raise ValueError(
                f"env.goal_radius={self.goal_radius!r} must be smaller than "
                f"env.interaction_radius={self.interaction_radius!r}"
            )
        if not self.interaction_radius < self.mediated_min_distance <= self.mediated_max_distance:
            raise ValueError(
                f"env.mediated_min_distance={self.mediated_min_distance!r} must exceed "
                f"env.interaction_radius={self.interaction_radius!r} and not exceed "
                f"env.mediated_max_distance={self.mediated_max_distance!r}"
            )
        if not self.mediated_max_distance + self.target_radius < self.world_radius:
            raise ValueError(
                f"env.world_radius={self.world_radius!r} must exceed env.mediated_max_distance + "
                f"env.target_radius = {self.mediated_max_distance!r} + {self.target_radius!r}: "
                "the wall must enclose the targets of target tasks"
            )

    @property
    def max_target_distance(self) -> float:
        """Upper bound of |M_i T| (both points lie inside the wall)."""
        return 2.0 * self.world_radius

    @property
    def max_origin_distance(self) -> float:
        """Upper bound of |M_i O|."""
        return self.world_radius

    @property
    def hook_end(self) -> tuple[float, float]:
        """M3 in the tool's frame (corner M2 at its origin, the handle along +x): (0, hook
        length) for the paper's L, exactly, so its curves do not change by a rounding."""
        if self.tool_hook_angle == 90.0:
            return 0.0, self.tool_hook_length
        angle = math.radians(self.tool_hook_angle)
        return self.tool_hook_length * math.cos(angle), self.tool_hook_length * math.sin(angle)

    # --- the mediator's shape: a world with another tool overrides these two ---------------
    @property
    def tool_points(self) -> tuple[tuple[float, float], ...]:
        """The tool's picking locations M1, M2, M3 in its body frame (the task's tool pose is
        that frame's origin and angle): the L's handle end, corner and hook end. They must span
        the tool (it lies in their convex hull): the range and wall checks test them alone."""
        return (self.tool_handle_length, 0.0), (0.0, 0.0), self.hook_end

    @property
    def tool_segments(self) -> tuple[tuple[tuple[float, float], tuple[float, float], float], ...]:
        """The tool's arms in its body frame, each (start, end, length), ``tool_width`` thick;
        ``tool_mass`` is spread over them by length."""
        return (((0.0, 0.0), (self.tool_handle_length, 0.0), self.tool_handle_length),
                ((0.0, 0.0), self.hook_end, self.tool_hook_length))

    def to_dict(self) -> dict:
        return asdict(self)
