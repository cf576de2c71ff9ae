"""The Gymnasium environment of the paper's world: mediated interaction with an L-shaped tool."""

from __future__ import annotations

import math
import operator
from collections.abc import Mapping

import gymnasium
import numpy as np
from gymnasium import spaces

from ..mapping import config_from_mapping
from .config import WorldConfig
from .task import NUM_DISTANCES, O, PICKING_LOCATIONS, SCENARIOS, T, Task, sample_task
from .world import World

# Actions: pick one of the five picking locations, move the picked object, turn the tool.
PICK_M1, PICK_M2, PICK_M3, PICK_T, PICK_O = range(5)
MOVE_OUT, MOVE_IN, MOVE_CCW, MOVE_CW = range(5, 9)
ROTATE_CCW, ROTATE_CW = 9, 10
NUM_ACTIONS = 11
ACTION_NAMES = (
    "pick M1", "pick M2", "pick M3", "pick T", "pick O",
    "move out", "move in", "move ccw", "move cw", "rotate ccw", "rotate cw",
)
RESET_OPTIONS = ("task",)

# A grip is lost only when contacts carried the active location out of range by more than
# rounding: driven moves end exactly on the range border at most.
_GRIP_TOLERANCE = 1e-9


class MediatedInteractionEnv(gymnasium.Env):
    """Bring a disc-shaped target into the goal area around the origin O, directly or with a tool.

    The paper's 2D world (its Figure 1): the agent reaches picking locations within the
    interaction range (radius 10) around O. A disc-shaped target and an L-shaped tool (the
    mediator) lie on a frictionless plane inside a circular wall, simulated with pymunk. The tool
    offers three picking locations, its handle end M1, its corner M2 and its hook end M3; the
    target one, its centre T; a fifth, O, is where every episode starts and is absorbing.

    ## Scenarios

    | scenario   | the paper's name                          | target centre                                    | tool               |
    |------------|-------------------------------------------|--------------------------------------------------|--------------------|
    | `"source"` | single-object interaction                 | in range, outside the goal area                  | all of it in range |
    | `"target"` | mediated interaction (extension of reach) | in the annulus `mediated_min/max_distance` (10.5-12.5) | all of it in range |

    The scenario only decides how `reset` samples a task; `reset(options={"task": task})` starts
    any valid task, so one environment serves a curriculum of source and target tasks.

    ## Action space

    `Discrete(11)`:

    | action | meaning |
    |--------|---------|
    | 0-4    | pick M1, M2, M3, T, O: that location becomes active; refused (a no-op) when it lies outside the interaction range |
    | 5      | move the active location `move_distance` radially out (away from O); in the tool frame along the handle, towards M1 |
    | 6      | move it radially in (towards O); in the tool frame along the handle, away from M1 |
    | 7      | move it tangentially, counter-clockwise around O; in the tool frame along the hook, towards M3 |
    | 8      | move it tangentially, clockwise; in the tool frame along the hook, away from M3 |
    | 9      | turn the tool by +`rotation_angle` (pi/4, counter-clockwise) around the active location |
    | 10     | turn it by -`rotation_angle` |

    A move carries the whole object holding the active location (the tool for M1-M3, the target
    for T) one `move_distance` along the frame of the moves, `move_frame` (the paper's "non-static
    coordinate system", its Figure 1b):

    | action | `move_frame="radial"` (default): at the active location P | `"tool"`, a tool location active | `"tool"`, T active |
    |--------|-------------------------------|----------------------------------------------------|------------|
    | 5      | out, along P/\\|P\\|            | along the handle, towards M1: (M1 - M2)/\\|M1 - M2\\| | as radial |
    | 6      | in, along -P/\\|P\\|            | along the handle, away from M1                     | as radial |
    | 7      | tangentially ccw around O     | along the hook, towards M3: (M3 - M2)/\\|M3 - M2\\|   | as radial |
    | 8      | tangentially cw               | along the hook, away from M3                       | as radial |

    The tool frame is the same whichever of M1, M2, M3 is held (it turns with the tool, not with
    the held location's position); the held location only decides the range check below.
    Refused (no-ops): any move or turn while O is active (O is absorbing); a turn while T is
    active; a radial move at O itself, where the radial frame is undefined; a move that would
    carry the active location out of the interaction range (so a held location never leaves the
    range by the agent's own hand); a move or turn that would carry the tool through the wall
    (kinematic bodies do not collide with static ones, so the wall is enforced here). Every
    step, refused or not, lasts `step_duration` simulated seconds, in which pushed objects
    coast and damp out. If contacts push the active location out of range, the grip is lost:
    O becomes active.

    Physics: the held object is driven kinematically (infinite mass) along the action's exact
    motion, in `substeps` pymunk steps; the other object is a dynamic body that it pushes, or
    with the hook drags, through contacts, without friction and with velocity damping
    (`damping` is the fraction kept per second). A pushed object coasts after the step; slower
    than `rest_speed` it stops, and a step that then moves nothing skips the physics.

    With probability `action_noise` (0.1) the chosen action is replaced by a uniformly random
    one, drawn from `self.np_random`.

    ## Observation space

    `Box(0, high, (11,), float64)`, the sensor vector of the paper's eq. (2):

    | index | observation | high |
    |-------|-------------|------|
    | 0-2   | distances \\|M1 T\\|, \\|M2 T\\|, \\|M3 T\\| from the tool's picking locations to the target's centre | 2 * world_radius |
    | 3-5   | distances \\|M1 O\\|, \\|M2 O\\|, \\|M3 O\\| to the origin | world_radius |
    | 6-10  | one-hot of the active picking location, in the order M1, M2, M3, T, O | 1 |

    The target's own distance to O is not observed.

    ## Rewards

    `success_reward` (10) on the step that brings the target's centre within `goal_radius` of O;
    0 on every other step.

    ## Starting state

    The task's poses with both objects at rest and O active. Without `options`, `reset` samples a
    task of the environment's scenario from `self.np_random`.

    ## Episode end

    * Termination: the target's centre lies within `goal_radius` of O (success).
    * Truncation: `max_episode_steps` (100) steps have passed.

    `info` holds `active_location` (index into M1, M2, M3, T, O) and `is_success`.

    ## Arguments

    `MediatedInteractionEnv(scenario="target", config=None, render_mode=None)`; `config` is a
    `WorldConfig` or a mapping of its fields (e.g. from Hydra), every constant of the world with
    its documented default. `render_mode="rgb_array"` draws the world as in the paper's Figure 1.

    ## Version history

    * v0: initial version; `move_frame` added later (its default, `"radial"`, is the frame v0
      always had, with bit-identical trajectories).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(
        self,
        scenario: str = "target",
        config: WorldConfig | Mapping | None = None,
        render_mode: str | None = None,
    ) -> None:
        if scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {scenario!r}; allowed: {', '.join(SCENARIOS)}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"unknown render_mode {render_mode!r}; allowed: None, "
                + ", ".join(self.metadata["render_modes"])
            )
        self.scenario = scenario
        self.config = config = _as_config(config)
        self.render_mode = render_mode
        self.action_space = spaces.Discrete(NUM_ACTIONS)
        high = np.array(
            [config.max_target_distance] * 3 + [config.max_origin_distance] * 3 + [1.0] * 5
        )
        self.observation_space = spaces.Box(0.0, high, dtype=np.float64)

        self._world = World(config)
        # Constants of the per-step path, read once.
        self._range = config.interaction_radius
        self._grip_range = config.interaction_radius + _GRIP_TOLERANCE
        self._goal = config.goal_radius
        self._noise = config.action_noise
        self._move = config.move_distance
        self._reward = float(config.success_reward)
        self._max_steps = config.max_episode_steps
        self._tool_limit = config.world_radius - config.tool_width / 2
        self._points = (m1, m2, m3) = config.tool_points
        self._lh, (self._hx, self._lk) = m1[0], m3
        if m1[1] != 0.0 or m2 != (0.0, 0.0):
            # Another mediator than an L with its corner at the body's origin (a world's
            # config.tool_points): instance attributes over the methods, as for move_frame, so
            # the paper's per-step path stays as it is.
            self._sense = self._sense_any_tool
            self._move_in_tool_frame = self._move_along_body_axes
        if config.move_frame == "tool":
            # An instance attribute over the method: the radial frame's step stays as it was.
            self._move_active = self._move_in_tool_frame
        half = config.rotation_angle / 2
        self._turns = {  # action -> (angle, cos/sin of the full and the half turn)
            ROTATE_CCW: (config.rotation_angle, *_cos_sin(2 * half), *_cos_sin(half)),
            ROTATE_CW: (-config.rotation_angle, *_cos_sin(-2 * half), *_cos_sin(-half)),
        }

        self._task: Task | None = None
        self._active = O
        self._steps = 0
        self._running = False
        # M1, M2, M3, T, O as a flat x, y list: location i is (_loc[2i], _loc[2i + 1]).
        self._loc = [0.0] * 10
        self._sensed = np.zeros(NUM_DISTANCES + len(PICKING_LOCATIONS))
        self._success = False
        self._uniforms: list[float] | tuple = ()
        self._next_uniform = 0
        self._renderer = None

    # --- Gymnasium API --------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        task = _task_from_options(options, self.config)
        super().reset(seed=seed)
        if task is None:
            task = sample_task(self.scenario, self.np_random, self.config)
        self._task = task
        self._world.place(task)
        self._active = O
        self._steps = 0
        self._running = True
        self._uniforms, self._next_uniform = (), 0
        self._sense()
        return self._observation(), {"active_location": O, "is_success": self._success}

    def step(self, action):
        if not self._running:
            raise RuntimeError("the episode is over (or never started): call reset() first")
        try:
            if isinstance(action, (bool, np.bool_)):  # an index, not a truth value
                raise TypeError
            a = operator.index(action)
        except TypeError:
            raise ValueError(
                f"action must be an integer in [0, {NUM_ACTIONS}), got {action!r}"
            ) from None
        if not 0 <= a < NUM_ACTIONS:
            raise ValueError(f"action must be an integer in [0, {NUM_ACTIONS}), got {a}")
        if self._noise and self._uniform() < self._noise:
            a = int(self._uniform() * NUM_ACTIONS)  # a uniformly random action instead

        physics_before = self._world.physics_steps
        self._act(a)
        if self._world.physics_steps != physics_before:  # else nothing moved
            self._sense()
            i = 2 * self._active
            if i != 2 * O and math.hypot(self._loc[i], self._loc[i + 1]) > self._grip_range:
                self._active = O  # contacts pushed the held location out of reach
        self._steps += 1
        success = self._success
        truncated = self._steps >= self._max_steps
        self._running = not (success or truncated)
        return (
            self._observation(),
            self._reward if success else 0.0,
            success,
            truncated,
            {"active_location": self._active, "is_success": success},
        )

    def render(self):
        if self.render_mode is None:
            gymnasium.logger.warn(
                "render() without a render_mode: create the environment with "
                'render_mode="rgb_array"'
            )
            return None
        if self._task is None:
            raise RuntimeError("call reset() before render()")
        if self._renderer is None:
            from .render import WorldRenderer  # PIL only when drawing

            self._renderer = WorldRenderer(self.config)
        return self._renderer.draw(self.picking_locations, self._active, self._steps, self.tool_arms)

    def close(self) -> None:
        """Release the renderer. A closed environment refuses ``step`` and ``reset`` (one line)
        instead of going on as if nothing happened; make a new one to go on."""
        self._renderer = None
        # Instance attributes over the methods, as for move_frame: the per-step path stays as
        # it is, so no run's code changes by being closable.
        self.step = self.reset = _closed
        super().close()

    # --- public read-only state (for scripted policies, curricula and plots) --------------------
    @property
    def picking_locations(self) -> np.ndarray:
        """Current M1, M2, M3, T, O as a 5 x 2 array (a copy)."""
        return np.array(self._loc).reshape(5, 2)

    @property
    def active_location(self) -> int:
        """Index of the active picking location in (M1, M2, M3, T, O)."""
        return self._active

    @property
    def tool_position(self) -> np.ndarray:
        """The tool's pose origin: the L's corner M2 (config.tool_points' body frame)."""
        return np.array((self._world.tool_x, self._world.tool_y))

    @property
    def tool_angle(self) -> float:
        """World angle of the handle, from M2 towards M1, in [-pi, pi)."""
        return (self._world.tool_angle + math.pi) % (2 * math.pi) - math.pi

    @property
    def tool_arms(self) -> list[tuple[tuple[float, float], tuple[float, float]]]:
        """The tool's arms (config.tool_segments) as (start, end) points in the world."""
        from .task import _to_world

        w = self._world
        c, s, origin = math.cos(w.tool_angle), math.sin(w.tool_angle), (w.tool_x, w.tool_y)
        return [(_to_world(a, origin, c, s), _to_world(b, origin, c, s)) for a, b, _ in self.config.tool_segments]

    @property
    def target_position(self) -> np.ndarray:
        """The target's centre T."""
        return np.array(self._loc[6:8])

    @property
    def task(self) -> Task | None:
        """The task the current episode started from."""
        return self._task

    @property
    def current_task(self) -> Task:
        """The current poses as task-space coordinates."""
        loc, w = self._loc, self._world
        return Task((loc[6], loc[7]), (w.tool_x, w.tool_y), self.tool_angle)

    @property
    def elapsed_steps(self) -> int:
        return self._steps

    @property
    def physics_steps(self) -> int:
        """Physics substeps (Chipmunk ``cpSpaceStep`` calls) made so far by this environment."""
        return self._world.physics_steps

    # --- one step -------------------------------------------------------------------------------
    def _act(self, a: int) -> None:
        world, active = self._world, self._active
        if a <= PICK_O:
            if a == O or math.hypot(self._loc[2 * a], self._loc[2 * a + 1]) <= self._range:
                self._active = a
            world.idle()
        elif active == O:
            world.idle()  # O is absorbing
        elif a <= MOVE_CW:
            self._move_active(a, active)
        elif active == T:
            world.idle()  # only the tool turns
        else:
            self._turn_tool(a, active)

    def _move_active(self, a: int, active: int) -> None:
        world, loc = self._world, self._loc
        x, y = loc[2 * active], loc[2 * active + 1]
        r = math.hypot(x, y)
        if r == 0.0:
            world.idle()  # no radial direction at O itself
            return
        ux, uy = x * self._move / r, y * self._move / r
        if a == MOVE_OUT:
            dx, dy = ux, uy
        elif a == MOVE_IN:
            dx, dy = -ux, -uy
        elif a == MOVE_CCW:
            dx, dy = -uy, ux
        else:
            dx, dy = uy, -ux
        if math.hypot(x + dx, y + dy) > self._range:
            world.idle()  # refused: the agent cannot carry a location out of its reach
        elif active == T:
            world.translate_target(dx, dy)
        elif (
            math.hypot(loc[0] + dx, loc[1] + dy) <= self._tool_limit
            and math.hypot(loc[2] + dx, loc[3] + dy) <= self._tool_limit
            and math.hypot(loc[4] + dx, loc[5] + dy) <= self._tool_limit
        ):
            world.translate_tool(dx, dy)
        else:
            world.idle()  # refused: the tool would pass through the wall

    _move_radially = _move_active

    def _move_in_tool_frame(self, a: int, active: int) -> None:
        """``move_frame="tool"``: a held tool moves along its own arms (see the class docstring)."""
        if active == T:
            self._move_radially(a, active)  # the target's disc has no orientation
            return
        loc = self._loc
        # Unit vectors from the sensed picking locations: e along the handle (M2 -> M1), h along
        # the hook (M2 -> M3), each scaled to one move.
        f = self._move / self._lh
        ex, ey = (loc[0] - loc[2]) * f, (loc[1] - loc[3]) * f
        if a == MOVE_OUT:
            dx, dy = ex, ey
        elif a == MOVE_IN:
            dx, dy = -ex, -ey
        elif a == MOVE_CCW:
            dx, dy = -ey, ex
        else:
            dx, dy = ey, -ex
        i = 2 * active
        if math.hypot(loc[i] + dx, loc[i + 1] + dy) > self._range:
            self._world.idle()  # refused: the agent cannot carry a location out of its reach
        elif (
            math.hypot(loc[0] + dx, loc[1] + dy) <= self._tool_limit
            and math.hypot(loc[2] + dx, loc[3] + dy) <= self._tool_limit
            and math.hypot(loc[4] + dx, loc[5] + dy) <= self._tool_limit
        ):
            self._world.translate_tool(dx, dy)
        else:
            self._world.idle()  # refused: the tool would pass through the wall

    def _turn_tool(self, a: int, pivot: int) -> None:
        angle, c, s, ch, sh = self._turns[a]
        loc, limit = self._loc, self._tool_limit
        px, py = loc[2 * pivot], loc[2 * pivot + 1]
        # The tool must stay inside the wall at the end and half-way through the turn.
        for j in (0, 2, 4):
            vx, vy = loc[j] - px, loc[j + 1] - py
            if (
                math.hypot(px + c * vx - s * vy, py + s * vx + c * vy) > limit
                or math.hypot(px + ch * vx - sh * vy, py + sh * vx + ch * vy) > limit
            ):
                self._world.idle()
                return
        self._world.rotate_tool(pivot, angle)

    def _uniform(self) -> float:
        # Uniform draws come from self.np_random in blocks: one call per step costs more than
        # the rest of the step's bookkeeping.
        if self._next_uniform == len(self._uniforms):
            self._uniforms, self._next_uniform = self.np_random.random(256).tolist(), 0
        self._next_uniform += 1
        return self._uniforms[self._next_uniform - 1]

    def _sense(self) -> None:
        """Read the poses after physics: picking locations, the six distances, success."""
        w, loc, h = self._world, self._loc, math.hypot
        c, s = math.cos(w.tool_angle), math.sin(w.tool_angle)
        x, y = w.tool_x, w.tool_y
        x1, y1 = x + self._lh * c, y + self._lh * s
        if self._hx == 0.0:  # the paper's L, as it always was computed
            x3, y3 = x - self._lk * s, y + self._lk * c
        else:
            x3, y3 = x + self._hx * c - self._lk * s, y + self._hx * s + self._lk * c
        tx, ty = w.target_x, w.target_y
        loc[0:8] = x1, y1, x, y, x3, y3, tx, ty
        # The observation without its one-hot: steps that move nothing only copy it. Written in
        # place (observations are copies of it), which costs half a new array.
        self._sensed[:NUM_DISTANCES] = (
            h(x1 - tx, y1 - ty), h(x - tx, y - ty), h(x3 - tx, y3 - ty), h(x1, y1), h(x, y),
            h(x3, y3),
        )
        self._success = h(tx, ty) <= self._goal

    def _sense_any_tool(self) -> None:
        """``_sense`` for any tool shape: its picking locations from config.tool_points."""
        w, loc, h = self._world, self._loc, math.hypot
        c, s = math.cos(w.tool_angle), math.sin(w.tool_angle)
        x, y, tx, ty = w.tool_x, w.tool_y, w.target_x, w.target_y
        for i, (px, py) in enumerate(self._points):
            loc[2 * i], loc[2 * i + 1] = x + px * c - py * s, y + px * s + py * c
        loc[6:8] = tx, ty
        self._sensed[:NUM_DISTANCES] = (
            *(h(loc[2 * i] - tx, loc[2 * i + 1] - ty) for i in range(3)),
            *(h(loc[2 * i], loc[2 * i + 1]) for i in range(3)),
        )
        self._success = h(tx, ty) <= self._goal

    def _move_along_body_axes(self, a: int, active: int) -> None:
        """``move_frame="tool"`` for any tool shape: along its body frame's x axis (5/6) and y
        axis (7/8), which for the paper's L are its handle and its hook."""
        if active == T:
            self._move_radially(a, active)
            return
        c, s = math.cos(self._world.tool_angle), math.sin(self._world.tool_angle)
        ex, ey = c * self._move, s * self._move
        dx, dy = {MOVE_OUT: (ex, ey), MOVE_IN: (-ex, -ey), MOVE_CCW: (-ey, ex), MOVE_CW: (ey, -ex)}[a]
        loc, i = self._loc, 2 * active
        if math.hypot(loc[i] + dx, loc[i + 1] + dy) > self._range:
            self._world.idle()
        elif all(math.hypot(loc[j] + dx, loc[j + 1] + dy) <= self._tool_limit for j in (0, 2, 4)):
            self._world.translate_tool(dx, dy)
        else:
            self._world.idle()

    def _observation(self) -> np.ndarray:
        observation = self._sensed.copy()
        observation[NUM_DISTANCES + self._active] = 1.0
        return observation


def _closed(*args, **kwargs):
    raise RuntimeError("the environment is closed: make a new one (close() released it)")


def _cos_sin(angle: float) -> tuple[float, float]:
    return math.cos(angle), math.sin(angle)


def _as_config(config) -> WorldConfig:
    if config is None:
        return WorldConfig()
    if isinstance(config, WorldConfig):
        return config
    if isinstance(config, Mapping):
        return config_from_mapping(WorldConfig, config, "env")
    raise ValueError(f"config must be a WorldConfig, a mapping or None, got {type(config).__name__}")


def _task_from_options(options, config: WorldConfig) -> Task | None:
    """The task ``reset`` was asked to start, validated; None to sample one."""
    if options is None:
        return None
    if not isinstance(options, Mapping):
        raise ValueError(
            f"reset options must be None or a dict with keys {RESET_OPTIONS}, "
            f"got {type(options).__name__}"
        )
    unknown = sorted(map(repr, set(options) - set(RESET_OPTIONS)))  # repr: one line, quoted
    if unknown:
        raise ValueError(
            f"unknown reset option(s) {', '.join(unknown)}; allowed: {', '.join(RESET_OPTIONS)}"
        )
    task = options.get("task")
    if task is None:
        return None
    if not isinstance(task, Task):
        try:
            task = Task.from_coordinates(task)
        except (TypeError, ValueError, OverflowError) as error:  # OverflowError: float(10**400)
            raise ValueError(
                "reset option 'task' must be a Task or its 5 task-space coordinates "
                f"(target x, y, tool corner x, y, tool angle): {error}"
            ) from None
    return task.validate(config)


__all__ = [
    "ACTION_NAMES", "MOVE_CCW", "MOVE_CW", "MOVE_IN", "MOVE_OUT", "MediatedInteractionEnv",
    "NUM_ACTIONS", "PICK_M1", "PICK_M2", "PICK_M3", "PICK_O", "PICK_T", "RESET_OPTIONS",
    "ROTATE_CCW", "ROTATE_CW",
]
