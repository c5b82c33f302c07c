"""The ``topdown`` observation: a semantic map of the floor drawn from the geometry with numpy (no renderer).

A square ``size x size`` uint8 image with one channel per kind of thing (:data:`CHANNELS`),
channels first (SB3's image convention). Pixel ``(row, col)`` covers the floor square whose
centre is ``x = left + (col + 0.5) * res``, ``y = top - (row + 0.5) * res`` (north up, as a
picture: row 0 is the largest ``y``), ``res = span / size`` metres.

Frames: ``"world"`` centres the map on the env's extent (the family's floor, or a fixed
scenario's area) and ``span`` defaults to the extent's longer side (7 m for the families:
about 0.11 m a pixel at 64 x 64); ``"robot"`` centres the same window on the base
(axis-aligned, not turned with the heading; floor beyond the extent is drawn as wall).

Values: a thing's pixels hold its *slot level*, ``255 - 224 * k // n`` for slot ``k`` of
``n`` (the capacity), so that a learner can tell slot 0 from slot 1 (the candidate phases
name items by slot); 0 is empty. Rectangles cover every pixel they overlap; discs cover
the pixels whose centres they contain and always the pixel holding their centre (an
object of 3.5 cm radius is one pixel at 64 x 64).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from fetchcarry_env.geometry import Rect, heading_vector
from fetchcarry_env.observation import WorldState
from fetchcarry_env.rules import clutter_rect
from fetchcarry_env.scenario import Scenario

CHANNELS: tuple[str, ...] = ("tables", "obstacles", "objects", "goals", "clutter", "robot", "held")
"""Channel order: tables; obstacles and walls (the floor outside the area); objects standing or
placed (not held); goals (each object's goal disc); clutter where it stands now; the robot's
disc (128) with its front half (255) showing the heading; the held object at the hand."""
FRAMES: tuple[str, ...] = ("world", "robot")
DEFAULT_SIZE = 64  # pixels a side
WALL = 255  # obstacle-channel value of the floor outside the area
ROBOT_BACK, ROBOT_FRONT = 128, 255  # robot-channel values of the rear and front halves of the base disc
_TABLES, _OBSTACLES, _OBJECTS, _GOALS, _CLUTTER, _ROBOT, _HELD = range(len(CHANNELS))


def slot_level(slot: int, slots: int) -> int:
    """The pixel value of slot ``slot`` of ``slots``: 255 for slot 0, falling by ``224 // slots`` a slot (>= 31)."""
    return 255 - (224 * slot) // max(slots, 1)


@dataclass
class TopdownMap:
    """Draws the ``topdown`` map of a scenario and state (see the module docstring).

    ``extent``: the floor the world frame shows (metres); ``capacity_*``: slots per kind
    (the slot levels' ``n``); ``size`` pixels a side; ``frame`` ``"world"`` or ``"robot"``;
    ``span`` metres a side (default: the extent's longer side).
    """

    extent: Rect
    capacity_tables: int
    capacity_obstacles: int
    capacity_objects: int
    capacity_clutter: int
    size: int = DEFAULT_SIZE
    frame: str = "world"
    span: float | None = None
    _static: tuple[object, np.ndarray] | None = field(default=None, repr=False)  # (scenario, 3 static layers)

    def __post_init__(self) -> None:
        if not isinstance(self.size, int) or isinstance(self.size, bool) or not 8 <= self.size <= 1024:
            raise ValueError(f"topdown size must be an integer from 8 to 1024 pixels, got {self.size!r}")
        if self.frame not in FRAMES:
            raise ValueError(f"topdown frame must be one of {', '.join(FRAMES)}, got {self.frame!r}")
        if self.span is None:
            self.span = float(max(self.extent.size))
        if not (math.isfinite(self.span) and self.span > 0):
            raise ValueError(f"topdown span must be a positive number of metres, got {self.span!r}")
        self.resolution = self.span / self.size  # metres a pixel
        centres = (np.arange(self.size) + 0.5) * self.resolution
        self._dx = centres  # offsets of pixel centres from the left edge (columns)
        self._dy = centres  # offsets of pixel centres from the top edge (rows, downwards)

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(channels, size, size)``."""
        return (len(CHANNELS), self.size, self.size)

    def window(self, state: WorldState) -> tuple[float, float]:
        """The map's ``(left, top)`` edge in metres for ``state`` (the frame's centre minus half the span)."""
        cx, cy = self.extent.center if self.frame == "world" else state.base
        half = self.span / 2
        return (cx - half, cy + half)

    def draw(self, scenario: Scenario, state: WorldState) -> np.ndarray:
        """The map (``uint8``, :attr:`shape`) of ``scenario`` at ``state``."""
        image = np.zeros(self.shape, dtype=np.uint8)
        left, top = self.window(state)
        image[[_TABLES, _OBSTACLES, _GOALS]] = self._static_layers(scenario, left, top)
        for k, item in enumerate(scenario.clutter):
            self._rect(image[_CLUTTER], clutter_rect(scenario, state, item.id), left, top, self._level(k, "clutter"))
        for k, obj in enumerate(scenario.objects):
            channel = _HELD if obj.id == state.holding else _OBJECTS
            x, y, _z = state.objects[obj.id]
            self._disc(image[channel], (x, y), obj.radius, left, top, self._level(k, "objects"))
        self._robot(image[_ROBOT], scenario, state, left, top)
        return image

    # ------------------------------------------------------------------ internals
    def _level(self, slot: int, kind: str) -> int:
        return slot_level(slot, getattr(self, f"capacity_{kind}"))

    def _static_layers(self, scenario: Scenario, left: float, top: float) -> np.ndarray:
        """Tables, obstacles with walls, goals: fixed for a scenario in the world frame (kept once)."""
        if self.frame == "world" and self._static is not None and self._static[0] is scenario:
            return self._static[1]
        layers = np.zeros((3, self.size, self.size), dtype=np.uint8)
        for k, table in enumerate(scenario.tables):
            self._rect(layers[0], table.rect, left, top, self._level(k, "tables"))
        area = scenario.area
        outside_x = (left + self._dx < area.min_x) | (left + self._dx > area.max_x)
        outside_y = (top - self._dy < area.min_y) | (top - self._dy > area.max_y)
        layers[1][outside_y[:, None] | outside_x[None, :]] = WALL
        for k, obstacle in enumerate(scenario.obstacles):
            self._rect(layers[1], obstacle.rect, left, top, slot_level(k + 1, self.capacity_obstacles + 1))
        for k, obj in enumerate(scenario.objects):
            self._disc(layers[2], obj.goal, obj.radius, left, top, self._level(k, "objects"))
        if self.frame == "world":
            self._static = (scenario, layers)
        return layers

    def _span(self, low: float, high: float) -> tuple[int, int]:
        """Pixel indices ``[first, last)`` a metric interval ``[low, high]`` (from the window's edge) overlaps."""
        first = max(0, math.floor(low / self.resolution))
        last = min(self.size, max(math.ceil(high / self.resolution), first + 1))
        return first, last

    def _rect(self, layer: np.ndarray, rect: Rect, left: float, top: float, value: int) -> None:
        c0, c1 = self._span(rect.min_x - left, rect.max_x - left)
        r0, r1 = self._span(top - rect.max_y, top - rect.min_y)
        if c0 < c1 and r0 < r1 and rect.max_x > left and top > rect.min_y:
            window = layer[r0:r1, c0:c1]
            np.maximum(window, value, out=window)

    def _disc_pixels(
        self, center: tuple[float, float], radius: float, left: float, top: float
    ) -> tuple[slice, slice, np.ndarray] | None:
        """The bounding window of a disc and which of its pixels it covers (always the one holding its centre)."""
        px, py = center[0] - left, top - center[1]
        c0, c1 = self._span(px - radius, px + radius)
        r0, r1 = self._span(py - radius, py + radius)
        if px + radius <= 0 or py + radius <= 0 or c0 >= c1 or r0 >= r1:
            return None
        ddx = self._dx[c0:c1] - px
        ddy = self._dy[r0:r1] - py
        inside = ddy[:, None] ** 2 + ddx[None, :] ** 2 <= radius * radius
        col, row = math.floor(px / self.resolution), math.floor(py / self.resolution)
        if c0 <= col < c1 and r0 <= row < r1:
            inside[row - r0, col - c0] = True
        return slice(r0, r1), slice(c0, c1), inside

    def _disc(
        self, layer: np.ndarray, center: tuple[float, float], radius: float, left: float, top: float, value: int
    ) -> None:
        found = self._disc_pixels(center, radius, left, top)
        if found is not None:
            rows, cols, inside = found
            window = layer[rows, cols]
            window[inside] = np.maximum(window[inside], value)

    def _robot(self, layer: np.ndarray, scenario: Scenario, state: WorldState, left: float, top: float) -> None:
        """The base disc at :data:`ROBOT_BACK`, its front half (the heading's side) at :data:`ROBOT_FRONT`."""
        radius = scenario.robot.radius
        found = self._disc_pixels(state.base, radius, left, top)
        if found is None:
            return
        rows, cols, inside = found
        hx, hy = heading_vector(state.heading)
        px, py = state.base[0] - left, top - state.base[1]
        ahead = (self._dx[cols] - px)[None, :] * hx - (self._dy[rows] - py)[:, None] * hy > 0
        layer[rows, cols][inside] = ROBOT_BACK
        layer[rows, cols][inside & ahead] = ROBOT_FRONT
