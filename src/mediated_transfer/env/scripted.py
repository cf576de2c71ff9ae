"""Scripted policies that solve the two scenarios, written against the environment's public API.

They prove the chosen geometry and physics allow the tasks to be solved: the tests require the
tool policy to bring >= 90 % of random target tasks, and the direct policy >= 95 % of random
source tasks, into the goal within the step limit. Both decide every step from the current
world state alone (no memory), so a random action (noise) or a bump only delays them.

Vocabulary of the tool policy: the tool frame has its origin at the corner M2, ``e`` along the
handle (towards M1) and ``h`` along the hook (towards M3). The L's inner quadrant (positive
coordinates along both) is the *cradle*: a target there is dragged by the hook when the tool
moves along +e and pushed by the handle when it moves along +h.
"""

from __future__ import annotations

import math

import numpy as np

from .mediated_env import (
    MOVE_CCW,
    MOVE_CW,
    MOVE_IN,
    MOVE_OUT,
    NUM_ACTIONS,
    PICK_M1,
    PICK_T,
    ROTATE_CCW,
    ROTATE_CW,
    MediatedInteractionEnv,
)
from .task import M1, M2, M3, T, _segment_distance

_MOVES = (MOVE_OUT, MOVE_IN, MOVE_CCW, MOVE_CW)


def _tool_gap(target: np.ndarray, tool: np.ndarray) -> float:
    """Distance from ``target`` to the nearer arm of the tool at locations ``tool`` (M1, M2, M3)."""
    return min(_segment_distance(target, tool[M2], tool[M1]), _segment_distance(target, tool[M2], tool[M3]))


def _move_direction(point: np.ndarray, action: int, handle: np.ndarray | None = None) -> np.ndarray:
    """Unit direction in which ``action`` moves a picking location at ``point``: in the radial
    frame at ``point``, or, given the tool's ``handle`` direction (M2 -> M1), in the tool frame
    (env.config.move_frame; the environment's action table)."""
    if handle is not None:
        u = handle
    else:
        r = math.hypot(point[0], point[1])
        if r == 0.0:
            return np.zeros(2)  # the environment refuses moves at O
        u = point / r
    return {MOVE_OUT: u, MOVE_IN: -u, MOVE_CCW: np.array([-u[1], u[0]]),
            MOVE_CW: np.array([u[1], -u[0]])}[action]


class ScriptedDirectPolicy:
    """Single-object interaction: pick the target and push it radially into the goal area."""

    def __init__(self, env) -> None:
        self.env: MediatedInteractionEnv = env.unwrapped

    def reset(self) -> None:
        """Nothing to forget: the policy has no memory."""

    def __call__(self, observation=None) -> int:
        return self.act(observation)

    def act(self, observation=None) -> int:
        env = self.env
        if env.active_location != T:
            return PICK_T  # refused while the target is out of reach
        return MOVE_IN


class ScriptedToolPolicy:
    """Mediated interaction: hook the target with the tool, pull it into reach, then push it in.

    1. Turn the tool (around a picking location whose sweep misses the target) to the one of
       its eight reachable angles that keeps M1 deepest in reach while the hook is behind the
       target.
    2. Holding M1: move the tool beside the target (its hook passing by laterally), out until
       the hook is behind the target, then sideways so the target enters the cradle.
    3. Pull: each step the move of M1 that brings the target closest to O while it stays on the
       hook.
    4. Once the target is in reach, behave like ScriptedDirectPolicy.

    Moves are predicted in the world's move frame (``move_frame``: radial or along the tool's
    arms), so the same policy solves both readings. If a turn left M1 out of reach, the tool is
    first moved, held where it can be, until M1 comes back into reach.
    """

    def __init__(self, env, clearance: float = 0.6) -> None:
        self.env: MediatedInteractionEnv = env.unwrapped
        c = self.env.config
        self.direct = ScriptedDirectPolicy(self.env)
        self.contact = c.target_radius + c.tool_width / 2  # centre distance at contact
        self.clearance = clearance  # wanted gap between target and tool while approaching
        self.lh, self.lk = c.tool_handle_length, c.tool_hook_length
        self.reach = c.interaction_radius
        self.tool_limit = c.world_radius - c.tool_width / 2
        self.turn = c.rotation_angle
        self.step_length = c.move_distance
        self.tool_frame = c.move_frame == "tool"  # moves of the held tool along its own arms

    def reset(self) -> None:
        """Nothing to forget: the policy has no memory."""

    def __call__(self, observation=None) -> int:
        return self.act(observation)

    # --- geometry ---------------------------------------------------------------------------------
    @staticmethod
    def _frame(angle: float) -> tuple[np.ndarray, np.ndarray]:
        e = np.array([math.cos(angle), math.sin(angle)])
        return e, np.array([-e[1], e[0]])

    def _m1_for(self, target: np.ndarray, angle: float, x: float, y: float) -> np.ndarray:
        """Where M1 must be for the target to sit at (x, y) in the tool frame of ``angle``."""
        e, h = self._frame(angle)
        return target + (self.lh - x) * e - y * h

    def _zones(self) -> tuple[float, float, float]:
        """Target coordinates in the tool frame: the approach x, and the y before/after the sweep."""
        x_approach = self.contact + self.clearance
        y_beside = self.lk + self.contact + self.clearance
        y_cradled = self.contact + 0.5 * self.clearance
        return x_approach, y_beside, y_cradled

    def _choose_angle(self, target: np.ndarray, angle: float) -> float:
        """Of the tool angles reachable by turns (the current one plus k * rotation_angle), the
        one that keeps M1 deepest in reach while the hook goes behind the target."""
        x_approach, y_beside, y_cradled = self._zones()

        def m1_radius(a: float) -> float:
            return max(
                float(np.linalg.norm(self._m1_for(target, a, x_approach, y_beside))),
                float(np.linalg.norm(self._m1_for(target, a, x_approach, y_cradled))),
            )

        turns = round(2 * math.pi / self.turn)
        return min((angle + k * self.turn for k in range(turns)), key=m1_radius)

    # --- policy ------------------------------------------------------------------------------------
    def act(self, observation=None) -> int:
        env = self.env
        locations = env.picking_locations
        target = locations[T]
        if math.hypot(*target) <= self.reach:
            return self.direct.act(observation)
        angle = env.tool_angle
        e, h = self._frame(angle)
        rel = target - locations[M2]
        x, y = float(rel @ e), float(rel @ h)
        # In the cradle, with the handle pointing inwards enough that dragging along it brings
        # the target nearer O (a long hook can hold a target the wrong way round).
        cradled = (self.contact - 0.3 <= x <= self.lh and self.contact - 0.3 <= y <= self.lk - 0.1
                   and float(e @ target) < -0.3 * math.hypot(*target))
        if not cradled:
            wanted = self._choose_angle(target, angle)
            if abs(math.remainder(wanted - angle, 2 * math.pi)) > 1e-6:
                return self._rotate_towards(locations, angle, wanted)
        if env.active_location != M1:
            if math.hypot(*locations[M1]) > self.reach:
                return self._bring_m1_into_reach(locations, e)  # e.g. after a turn around M2
            return PICK_M1  # M1 is the handle's end: the tool is moved by it from here on
        if cradled:
            return self._pull(locations, e, h, x, y)
        return self._approach(locations, e, h, x, y)

    def _approach(self, locations, e, h, x, y) -> int:
        """Bring the target, in tool coordinates, around the hook's tip into the cradle."""
        x_approach, y_beside, y_cradled = self._zones()
        stage = self._stage(x, y)
        goal = {
            0: (-(self.contact + self.clearance), y),  # near the tool: back off towards O
            1: (min(x, -(self.contact + self.clearance)), y_beside),  # sideways past the hook
            2: (x_approach, y_beside),  # beside the hook's tip: out until the hook is behind
            3: (x_approach, y_cradled),  # sideways: the hook passes behind the target
        }[stage]
        return self._move_m1_to(locations, e, h, goal, stage)

    def _stage(self, x: float, y: float) -> int:
        """How far the approach has come, from the target's tool coordinates (x, y)."""
        x_approach, y_beside, _ = self._zones()
        above_tip = y >= self.lk + self.contact + 0.1
        # Above the tip, only a target just beside it is ready for the sweep (from far above,
        # going down to it counts as stage 2, so its moves never fall back a stage).
        if x >= self.contact + 0.1 and y >= self.contact and (
            not above_tip or (abs(x - x_approach) <= 0.7 and y <= y_beside + 1.0)
        ):
            return 3
        if above_tip:
            return 2
        if x <= -self.contact:
            return 1
        return 0

    def _tool_gap(self, x: float, y: float) -> float:
        """Gap between the target at (x, y) in the tool frame and the tool."""
        to_handle = math.hypot(x - min(max(x, 0.0), self.lh), y)
        to_hook = math.hypot(x, y - min(max(y, 0.0), self.lk))
        return min(to_handle, to_hook) - self.contact

    def _tool_step(self, point: np.ndarray, action: int, e: np.ndarray) -> np.ndarray:
        """How far ``action`` moves the tool held at ``point`` (``e``: the handle's direction)."""
        return self.step_length * _move_direction(point, action, e if self.tool_frame else None)

    def _move_m1_to(self, locations, e, h, goal, stage: int) -> int:
        """The move of M1 that brings the target's tool coordinates closest to ``goal``
        without touching the tool, preferring moves that do not fall back a stage."""
        m1, target, m2 = locations[M1], locations[T], locations[M2]
        best, best_key = MOVE_IN, None
        for action in _MOVES:
            step = self._tool_step(m1, action, e)
            if not self._allowed(locations, step):
                continue
            rel = target - (m2 + step)
            x, y = float(rel @ e), float(rel @ h)
            if self._tool_gap(x, y) < 0.1:
                continue
            key = (self._stage(x, y) >= stage, -math.hypot(x - goal[0], y - goal[1]))
            if best_key is None or key > best_key:
                best, best_key = action, key
        return best

    def _allowed(self, locations, step, held: int = M1) -> bool:
        """Whether the environment accepts moving the tool (held at ``held``) by ``step``."""
        if np.linalg.norm(locations[held] + step) > self.reach:
            return False
        return bool(np.all(np.linalg.norm(locations[:3] + step, axis=1) <= self.tool_limit))

    def _pull(self, locations, e, h, x, y) -> int:
        """The move of M1 that brings the target closest to O while the hook keeps it."""
        target, m1 = locations[T], locations[M1]
        best, best_radius = None, math.inf
        for action in _MOVES:
            step = self._tool_step(m1, action, e)
            if not self._allowed(locations, step):
                continue
            along_e, along_h = float(step @ e), float(step @ h)
            # The hook pushes the target along e once the gap closes; the handle along h.
            push_e = max(0.0, along_e - (x - self.contact))
            push_h = max(0.0, along_h - (y - self.contact))
            new_y = y - along_h + push_h
            # Near the hook's end, a move along the hook first sinks the target deeper into the
            # cradle (the tool frame's moves keep the target's y on a lattice of unit steps).
            deeper = y > self.lk - 0.35 and self.contact <= new_y < y
            if push_e <= 0.0 and push_h <= 0.0 and along_e <= 0.0 and not deeper:
                continue  # leaves the target behind
            if new_y > self.lk - 0.35:
                continue  # would slide off the hook's end
            radius = math.hypot(*(target + push_e * e + push_h * h))
            if radius < best_radius:
                best, best_radius = action, radius
        return best if best is not None else MOVE_IN

    def _rotate_towards(self, locations, angle: float, wanted: float) -> int:
        turns = round(math.remainder(wanted - angle, 2 * math.pi) / self.turn)
        action = ROTATE_CCW if turns > 0 else ROTATE_CW
        signed = self.turn if turns > 0 else -self.turn
        active = self.env.active_location
        # Prefer turning around the held location; else pick the safest one in reach.
        candidates = [i for i in (M1, M2, M3) if np.linalg.norm(locations[i]) <= self.reach]
        safe = [i for i in candidates if self._turn_clearance(locations, i, signed) > 0.2]
        if active in safe:
            return action
        if safe:
            return safe[0]  # pick actions 0-2 are the indices of M1-M3
        return self._back_off(locations)

    def _turn_clearance(self, locations, pivot: int, turn: float) -> float:
        """Smallest gap between target and tool while turning by ``turn`` around ``pivot``."""
        target, p = locations[T], locations[pivot]
        gap = math.inf
        for fraction in np.linspace(0.0, 1.0, 7):
            c, s = math.cos(fraction * turn), math.sin(fraction * turn)
            rot = np.array([[c, -s], [s, c]])
            m1, m2, m3 = ((rot @ (locations[i] - p)) + p for i in (M1, M2, M3))
            if np.any(np.linalg.norm(np.array([m1, m2, m3]), axis=1) > self.tool_limit):
                return -math.inf  # the environment would refuse the turn
            gap = min(gap, _segment_distance(target, m2, m1), _segment_distance(target, m2, m3))
        return gap - self.contact

    def _bring_m1_into_reach(self, locations, e) -> int:
        """Hold the tool where it can be held and move it so that M1 comes closest to O,
        keeping clear of the target."""
        active = self.env.active_location
        if active not in (M1, M2, M3):
            return self._pick_reachable(locations)
        target, p = locations[T], locations[active]
        best, best_radius = None, math.inf
        for action in _MOVES:
            step = self._tool_step(p, action, e)
            if not self._allowed(locations, step, active):
                continue
            moved = locations[:3] + step
            gap = _tool_gap(target, moved) - self.contact
            radius = float(np.linalg.norm(moved[M1]))
            if gap >= 0.1 and radius < best_radius:
                best, best_radius = action, radius
        return best if best is not None else self._back_off(locations)

    def _pick_reachable(self, locations) -> int:
        reachable = [i for i in (M2, M1, M3) if np.linalg.norm(locations[i]) <= self.reach]
        return reachable[0] if reachable else PICK_M1

    def _back_off(self, locations) -> int:
        """No turn is safe: move the tool (held anywhere in reach) away from the target."""
        active = self.env.active_location
        if active not in (M1, M2, M3):
            return self._pick_reachable(locations)
        target, p = locations[T], locations[active]
        e = self._frame(self.env.tool_angle)[0]
        best, best_gap = MOVE_IN, -math.inf
        for action in _MOVES:
            step = self._tool_step(p, action, e)
            if not self._allowed(locations, step, active):
                continue
            gap = _tool_gap(target, locations[:3] + step)
            if gap > best_gap:
                best, best_gap = action, gap
        return best


def random_success_rate(world=None, episodes: int = 20_000, seed: int = 0,
                        scenario: str = "target") -> float:
    """Share of ``episodes`` random tasks of ``scenario`` that uniformly random actions solve:
    how rare a learner's first reward is before it has learned anything (discovery).

    ``world`` is a WorldConfig or a mapping of its fields (None: the default world); the
    environment's action noise applies as configured. The tasks come from the environment's
    generator, seeded once, and the actions from a second, independent stream, both derived
    from ``seed``: the same arguments always give the same rate.
    """
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes must be an integer >= 1, got {episodes!r}")
    env = MediatedInteractionEnv(scenario, world)
    task_seed, action_seed = (int(np.random.SeedSequence([seed, stream]).generate_state(1)[0])
                              for stream in (1, 2))
    actions = np.random.default_rng(action_seed)
    limit = env.config.max_episode_steps
    successes = 0
    env.reset(seed=task_seed)
    for episode in range(episodes):
        if episode:
            env.reset()
        for action in actions.integers(NUM_ACTIONS, size=limit).tolist():
            _, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                break
        successes += terminated
    return successes / episodes
