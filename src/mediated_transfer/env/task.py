"""Task instances c = (s, t) and the random source/target task samplers.

A task is given by its task-space coordinates t (target position, tool pose); its sensor vector
s is eq. (2) of the paper at the episode's start, when the agent's active picking location is
the origin O.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .config import WorldConfig

# Order of the picking locations: the one-hot A_pos of eq. (2) and the pick actions use it.
PICKING_LOCATIONS = ("M1", "M2", "M3", "T", "O")
M1, M2, M3, T, O = range(5)
SCENARIOS = ("source", "target")

#: Sensor vector layout (eq. 2): |M1T| |M2T| |M3T| |M1O| |M2O| |M3O| then the 5-dim one-hot.
NUM_DISTANCES = 6
OBSERVATION_SIZE = NUM_DISTANCES + len(PICKING_LOCATIONS)


def tool_picking_locations(tool_position, tool_angle: float, config: WorldConfig) -> np.ndarray:
    """M1 (handle end), M2 (the L's corner, its middle) and M3 (hook end) in world coordinates.

    The tool frame has its origin at the corner M2, the handle along its x axis and the hook
    along its y axis; ``tool_angle`` is the world angle of that x axis.
    """
    return np.array(_tool_points(tool_position, tool_angle, config))


def sensor_vector(
    tool_locations: np.ndarray, target_position, active: int = O
) -> np.ndarray:
    """Eq. (2): distances M_i-T, M_i-O and the one-hot of the active picking location."""
    obs = np.zeros(OBSERVATION_SIZE)
    tx, ty = target_position
    for i in range(3):
        x, y = tool_locations[i]
        obs[i] = math.hypot(x - tx, y - ty)
        obs[3 + i] = math.hypot(x, y)
    obs[NUM_DISTANCES + active] = 1.0
    return obs


def sensor_vectors(tasks, world: WorldConfig = WorldConfig()) -> np.ndarray:
    """The tasks' sensor vectors s (eq. 2, active location O), one row per task."""
    out = np.empty((len(tasks), OBSERVATION_SIZE))
    for i, task in enumerate(tasks):
        out[i] = task.sensor_vector(world)
    return out


# Plain floats below: every reset samples and validates a task, and numpy's per-call cost on
# 2-vectors made that slower than a hundred environment steps.
def _tool_points(tool_position, tool_angle: float, config: WorldConfig):
    """M1, M2, M3 as (x, y) tuples (see tool_picking_locations)."""
    return tuple(_to_world(p, tool_position, math.cos(tool_angle), math.sin(tool_angle))
                 for p in config.tool_points)


def _to_world(point, origin, c: float, s: float) -> tuple[float, float]:
    # For the paper's L (zeros in its points) this is bit for bit the formula it always had.
    px, py = point
    return origin[0] + px * c - py * s, origin[1] + px * s + py * c


def _tool_gap(target, tool_position, tool_angle: float, config: WorldConfig) -> float:
    """Distance from ``target`` to the nearest of the tool's arms (config.tool_segments)."""
    c, s = math.cos(tool_angle), math.sin(tool_angle)
    return min(_segment_distance(target, _to_world(a, tool_position, c, s), _to_world(b, tool_position, c, s))
               for a, b, _ in config.tool_segments)


def _segment_distance(p, a, b) -> float:
    abx, aby = b[0] - a[0], b[1] - a[1]
    apx, apy = p[0] - a[0], p[1] - a[1]
    t = min(1.0, max(0.0, (apx * abx + apy * aby) / (abx * abx + aby * aby)))
    return math.hypot(apx - t * abx, apy - t * aby)


@dataclass(frozen=True)
class Task:
    """One task instance in task-space coordinates t = (target x, y, tool corner x, y, angle)."""

    target_position: tuple[float, float]
    tool_position: tuple[float, float]
    tool_angle: float

    @property
    def coordinates(self) -> np.ndarray:
        """t as a flat vector."""
        return np.array([*self.target_position, *self.tool_position, self.tool_angle])

    @classmethod
    def from_coordinates(cls, t) -> "Task":
        t = [float(v) for v in t]
        if len(t) != 5:
            raise ValueError(f"a task has 5 task-space coordinates, got {len(t)}")
        return cls((t[0], t[1]), (t[2], t[3]), t[4])

    def picking_locations(self, config: WorldConfig = WorldConfig()) -> np.ndarray:
        """The five picking locations M1, M2, M3, T, O (shape 5 x 2)."""
        tool = tool_picking_locations(self.tool_position, self.tool_angle, config)
        return np.vstack([tool, [self.target_position], [[0.0, 0.0]]])

    def sensor_vector(self, config: WorldConfig = WorldConfig()) -> np.ndarray:
        """s: the observation at the start of an episode on this task (active location O)."""
        tool = tool_picking_locations(self.tool_position, self.tool_angle, config)
        return sensor_vector(tool, self.target_position, O)

    @property
    def target_distance(self) -> float:
        return math.hypot(*self.target_position)

    def problems(self, config: WorldConfig = WorldConfig()) -> list[str]:
        """Why this task cannot start an episode (empty when it can)."""
        out = _field_problems(self)
        if out:  # the geometry below would fail on them, or measure the wrong thing
            return out
        if not all(math.isfinite(v) for v in (*self.target_position, *self.tool_position,
                                              self.tool_angle)):
            out.append(f"task coordinates must be finite, got {self.coordinates.tolist()}")
            return out
        points = _tool_points(self.tool_position, self.tool_angle, config)
        target = self.target_position
        limit = config.world_radius - config.target_radius
        if math.hypot(*target) > limit:
            out.append(f"target centre lies outside the world (|T| > {limit:g})")
        tool_limit = config.world_radius - config.tool_width / 2
        if any(math.hypot(*p) > tool_limit for p in points):
            out.append(f"tool lies outside the world (a picking location beyond {tool_limit:g})")
        clearance = config.target_radius + config.tool_width / 2
        gap = _tool_gap(target, self.tool_position, self.tool_angle, config)
        if gap < clearance:
            out.append(f"target and tool overlap (gap {gap:.3f} < {clearance:g})")
        return out

    def validate(self, config: WorldConfig = WorldConfig()) -> "Task":
        problems = self.problems(config)
        if problems:
            raise ValueError("invalid task " + repr(self) + ": " + "; ".join(problems))
        return self


def _field_problems(task: Task) -> list[str]:
    """Each field of ``task`` that is not of its kind: a position is 2 real numbers (x, y), the
    angle one (radians)."""
    out = [f"{name} must be 2 numbers (x, y), got {value!r}"
           for name, value in (("target_position", task.target_position), ("tool_position", task.tool_position))
           if not (isinstance(value, (tuple, list, np.ndarray)) and len(value) == 2 and all(map(_real, value)))]
    if not _real(task.tool_angle):
        out.append(f"tool_angle must be a number (radians), got {task.tool_angle!r}")
    return out


def _real(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def _uniform_in_annulus(rng: np.random.Generator, r_min: float, r_max: float) -> tuple[float, float]:
    # Area-uniform: the radius' square is uniform.
    r = math.sqrt(rng.uniform(r_min * r_min, r_max * r_max))
    phi = rng.uniform(0.0, 2.0 * math.pi)
    return (r * math.cos(phi), r * math.sin(phi))


MAX_DRAWS = 1_000_000
"""Random candidates ``sample_task`` draws before it gives up: sizes that leave no room for a
task (a tool longer than the range) would otherwise loop forever. RunSpec.validate refuses
such sizes before a run (``sampling_rate``); valid worlds keep a candidate in a few draws."""


def _sample_tool_in_range(rng: np.random.Generator, config: WorldConfig, draws: list[int]):
    # Uniform corner in the range and uniform angle, kept when all three picking locations
    # are reachable (so the whole tool, a convex hull of them, lies inside the range).
    while True:
        _count_draw(draws, config)
        position = _uniform_in_annulus(rng, 0.0, config.interaction_radius)
        angle = float(rng.uniform(-math.pi, math.pi))
        if _tool_in_range(position, angle, config):
            return position, angle


def _tool_in_range(position, angle: float, config: WorldConfig) -> bool:
    points = _tool_points(position, angle, config)
    return all(math.hypot(*p) <= config.interaction_radius for p in points)


def _count_draw(draws: list[int], config: WorldConfig) -> None:
    draws[0] += 1
    if draws[0] > MAX_DRAWS:
        raise ValueError(f"no valid task in {MAX_DRAWS} random draws: {_sizes(config)} leave no room for one")


def _sizes(config: WorldConfig) -> str:
    keys = ("interaction_radius", "goal_radius", "target_radius", "tool_handle_length",
            "tool_hook_length", "tool_width", "mediated_min_distance", "mediated_max_distance",
            "world_radius")
    return ", ".join(f"env.{k}={getattr(config, k)!r}" for k in keys)


@functools.lru_cache(maxsize=64)  # validation asks again for the same world
def sampling_rate(scenario: str, config: WorldConfig, draws: int = 2000) -> float:
    """Fraction of random candidates (target, tool) that ``sample_task`` would keep, from a
    fixed generator: how much room the world's sizes leave for a task of ``scenario``."""
    rng = np.random.default_rng(0)
    kept = 0
    for _ in range(draws):
        target = _target_candidate(scenario, rng, config)
        position = _uniform_in_annulus(rng, 0.0, config.interaction_radius)
        angle = float(rng.uniform(-math.pi, math.pi))
        kept += _tool_in_range(position, angle, config) and not Task(target, position, angle).problems(config)
    return kept / draws


def check_room(scenario: str, config: WorldConfig, min_rate: float = 0.01) -> None:
    """ValueError naming the sizes if under ``min_rate`` of random candidates make a valid task
    (sampling would take 1/rate draws per task, and never end when no task fits)."""
    rate = sampling_rate(scenario, config)
    if rate < min_rate:
        raise ValueError(f"{_sizes(config)} leave room for {scenario} tasks in {rate:.2%} of random "
                         f"placements (at least {min_rate:.0%} needed): change these sizes")


def _target_candidate(scenario: str, rng: np.random.Generator, config: WorldConfig):
    if scenario == "source":
        # Keep the whole target disc inside the range and out of the goal area.
        return _uniform_in_annulus(rng, config.goal_radius, config.interaction_radius - config.target_radius)
    return _uniform_in_annulus(rng, config.mediated_min_distance, config.mediated_max_distance)


def sample_task(scenario: str, rng: np.random.Generator, config: WorldConfig = WorldConfig()) -> Task:
    """A random task of a scenario.

    source ("single-object interaction"): target and tool uniformly inside the interaction
    range, the target outside the goal area. target ("mediated interaction", extension of
    reach): the target uniformly in the annulus [mediated_min_distance, mediated_max_distance],
    out of reach; the tool inside the range.
    """
    if scenario not in SCENARIOS:
        raise ValueError(f"unknown scenario {scenario!r}; allowed: {', '.join(SCENARIOS)}")
    draws = [0]
    while True:
        _count_draw(draws, config)
        target = _target_candidate(scenario, rng, config)
        position, angle = _sample_tool_in_range(rng, config, draws)
        task = Task(target, position, angle)
        if not task.problems(config):
            return task


def sample_tasks(
    scenario: str, n: int, rng: np.random.Generator, config: WorldConfig = WorldConfig()
) -> list[Task]:
    return [sample_task(scenario, rng, config) for _ in range(n)]
