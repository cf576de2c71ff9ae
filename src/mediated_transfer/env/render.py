"""Draw the world as in the paper's Figure 1: range circle, goal area, target, tool, picking locations."""

from __future__ import annotations

import math

import numpy as np
from PIL import Image, ImageDraw

from .config import WorldConfig
from .task import O, PICKING_LOCATIONS, T

WHITE = (255, 255, 255)
WALL = (150, 150, 150)
GOAL = (205, 205, 205)
RANGE = (70, 110, 190)
SENSOR = (220, 60, 60)
TARGET = (245, 200, 30)
TOOL = (240, 140, 30)
OUTLINE = (40, 40, 40)
DOT = (0, 0, 0)
ACTIVE = (220, 30, 30)

# Drawn at this multiple of the output size, then scaled down: PIL draws without antialiasing.
_SUPERSAMPLE = 2


class WorldRenderer:
    """Draws frames of one world geometry; ``draw`` returns an RGB uint8 array (size x size x 3)."""

    def __init__(self, config: WorldConfig, size: int = 480, show_sensors: bool = True) -> None:
        if size < 32:
            raise ValueError(f"render size must be >= 32 pixels, got {size}")
        self.config = config
        self.size = size
        self.show_sensors = show_sensors
        self._px = size * _SUPERSAMPLE
        extent = config.world_radius + config.wall_thickness + 0.5
        self._scale = self._px / (2 * extent)  # pixels per world unit

    def _xy(self, x: float, y: float) -> tuple[float, float]:
        # World y points up, image rows go down.
        half = self._px / 2
        return half + x * self._scale, half - y * self._scale

    def to_pixel(self, x: float, y: float) -> tuple[int, int]:
        """(column, row) of the world point (x, y) in a drawn frame."""
        column, row = self._xy(x, y)
        return int(column / _SUPERSAMPLE), int(row / _SUPERSAMPLE)

    def _disc(self, draw, x, y, radius_world=None, radius_px=None, **style) -> None:
        r = radius_px * _SUPERSAMPLE if radius_px is not None else radius_world * self._scale
        cx, cy = self._xy(x, y)
        draw.ellipse((cx - r, cy - r, cx + r, cy + r), **style)

    def _dotted(self, draw, a, b, color, dash_px: float = 6.0) -> None:
        (ax, ay), (bx, by) = self._xy(*a), self._xy(*b)
        length = math.hypot(bx - ax, by - ay)
        n = max(1, int(length / (2 * dash_px * _SUPERSAMPLE)))
        for k in range(n):
            t0, t1 = k / n, (k + 0.5) / n
            draw.line(
                (ax + t0 * (bx - ax), ay + t0 * (by - ay), ax + t1 * (bx - ax), ay + t1 * (by - ay)),
                fill=color,
                width=_SUPERSAMPLE,
            )

    def draw(
        self, locations: np.ndarray, active: int, step: int | None = None, arms=None
    ) -> np.ndarray:
        """One frame: ``locations`` are M1, M2, M3, T, O (5 x 2), ``active`` an index into them;
        ``arms`` the tool's segments as (start, end) world points (None: the L's, M2-M1 and
        M2-M3)."""
        c = self.config
        image = Image.new("RGB", (self._px, self._px), WHITE)
        draw = ImageDraw.Draw(image)

        # Wall (a ring), goal area (shaded), interaction range (dashed circle).
        self._disc(draw, 0, 0, c.world_radius + c.wall_thickness, fill=WALL)
        self._disc(draw, 0, 0, c.world_radius, fill=WHITE)
        self._disc(draw, 0, 0, c.goal_radius, fill=GOAL)
        r = c.interaction_radius * self._scale
        cx, cy = self._xy(0, 0)
        for start in range(0, 360, 6):
            draw.arc((cx - r, cy - r, cx + r, cy + r), start, start + 3, fill=RANGE,
                     width=2 * _SUPERSAMPLE)

        tool = [tuple(p) for p in locations[:3]]
        target = tuple(locations[T])
        if self.show_sensors:  # the sensor distances of eq. (2), dotted red as in Figure 1a
            for p in tool:
                self._dotted(draw, p, target, SENSOR)
                self._dotted(draw, p, (0.0, 0.0), SENSOR)

        self._disc(draw, *target, c.target_radius, fill=TARGET, outline=OUTLINE,
                   width=_SUPERSAMPLE)
        # The tool's arms (the L: handle M2-M1 and hook M2-M3) as thick lines with round ends.
        width = max(1, round(c.tool_width * self._scale))
        if arms is None:
            arms = [(tool[1], tool[0]), (tool[1], tool[2])]
        for start, end in arms:
            draw.line((*self._xy(*start), *self._xy(*end)), fill=TOOL, width=width)
        for p in {tuple(map(float, point)) for arm in arms for point in arm}:
            self._disc(draw, *p, c.tool_width / 2, fill=TOOL)

        for i, p in enumerate(locations):
            if i == active:
                self._disc(draw, *p, radius_px=7, outline=ACTIVE, width=2 * _SUPERSAMPLE)
                self._disc(draw, *p, radius_px=3.5, fill=ACTIVE)
            else:
                self._disc(draw, *p, radius_px=3, fill=DOT)

        label = f"active {PICKING_LOCATIONS[active]}"
        if step is not None:
            label = f"step {step}   " + label
        if active == O:
            label += " (absorbing)"
        draw.text((8 * _SUPERSAMPLE, 6 * _SUPERSAMPLE), label, fill=OUTLINE,
                  font_size=13 * _SUPERSAMPLE)

        image = image.resize((self.size, self.size), Image.LANCZOS)
        return np.asarray(image, dtype=np.uint8).copy()
