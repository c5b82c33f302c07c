"""Pure planar geometry of the fetch-and-carry world.

Everything here is 2-D, axis-aligned and exact: rectangles (tables, obstacles, clutter),
discs (the robot base, delivery objects), segments (base moves, the arm line) and the
four headings of the paper. No PyBullet, no solver: the planner, the validator, the
scenario generator and the simulator all share these definitions.

Units are metres; angles are the four headings ``+x``, ``+y``, ``-x``, ``-y``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Literal

Point = tuple[float, float]
"""A point ``(x, y)`` in the world frame, metres."""

Heading = Literal["+x", "+y", "-x", "-y"]
"""Where the robot faces: the paper's forward, left, backward and right."""

HEADINGS: tuple[Heading, ...] = ("+x", "+y", "-x", "-y")
"""The four headings in counter-clockwise order; index k is a yaw of k * 90 degrees."""

_UNIT: dict[str, tuple[int, int]] = {"+x": (1, 0), "+y": (0, 1), "-x": (-1, 0), "-y": (0, -1)}

EPS = 1e-9  # metres: tolerance of exact comparisons


def heading_vector(heading: Heading) -> tuple[int, int]:
    """Unit vector (world frame) of a heading."""
    return _UNIT[heading]


def heading_yaw(heading: Heading) -> float:
    """Yaw of a heading in radians (``+x`` is 0, counter-clockwise positive)."""
    return HEADINGS.index(heading) * math.pi / 2


def heading_of(direction: Point) -> Heading | None:
    """The heading an axis-aligned direction points along, or None if it is diagonal or zero."""
    dx, dy = direction
    if abs(dy) <= EPS and abs(dx) > EPS:
        return "+x" if dx > 0 else "-x"
    if abs(dx) <= EPS and abs(dy) > EPS:
        return "+y" if dy > 0 else "-y"
    return None


def to_robot_frame(heading: Heading, dx: float, dy: float) -> tuple[float, float]:
    """World offset -> ``(forward, lateral)`` in the robot frame (lateral = 90 degrees left)."""
    hx, hy = _UNIT[heading]
    return (dx * hx + dy * hy, -dx * hy + dy * hx)


def to_world_frame(heading: Heading, forward: float, lateral: float) -> tuple[float, float]:
    """Robot-frame ``(forward, lateral)`` -> world offset ``(dx, dy)``."""
    hx, hy = _UNIT[heading]
    return (forward * hx - lateral * hy, forward * hy + lateral * hx)


@dataclass(frozen=True)
class Rect:
    """An axis-aligned rectangle ``[min_x, max_x] x [min_y, max_y]`` in metres."""

    min_x: float
    min_y: float
    max_x: float
    max_y: float

    @classmethod
    def from_corners(cls, lo: Sequence[float], hi: Sequence[float]) -> Rect:
        return cls(float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))

    @classmethod
    def around(cls, center: Point, half_x: float, half_y: float) -> Rect:
        """The rectangle of half-sizes ``half_x``, ``half_y`` centred at ``center``."""
        cx, cy = center
        return cls(cx - half_x, cy - half_y, cx + half_x, cy + half_y)

    @property
    def min(self) -> Point:
        return (self.min_x, self.min_y)

    @property
    def max(self) -> Point:
        return (self.max_x, self.max_y)

    @property
    def center(self) -> Point:
        return ((self.min_x + self.max_x) / 2, (self.min_y + self.max_y) / 2)

    @property
    def size(self) -> tuple[float, float]:
        return (self.max_x - self.min_x, self.max_y - self.min_y)

    @property
    def is_proper(self) -> bool:
        """True when ``min < max`` on both axes."""
        return self.min_x < self.max_x and self.min_y < self.max_y

    def inflate(self, margin: float) -> Rect:
        """The rectangle grown by ``margin`` on every side (shrunk when negative)."""
        return Rect(self.min_x - margin, self.min_y - margin, self.max_x + margin, self.max_y + margin)

    def translate(self, dx: float, dy: float) -> Rect:
        return Rect(self.min_x + dx, self.min_y + dy, self.max_x + dx, self.max_y + dy)

    def contains_point(self, p: Point, tol: float = EPS) -> bool:
        return self.min_x - tol <= p[0] <= self.max_x + tol and self.min_y - tol <= p[1] <= self.max_y + tol

    def contains_rect(self, other: Rect, tol: float = EPS) -> bool:
        return (
            other.min_x >= self.min_x - tol
            and other.min_y >= self.min_y - tol
            and other.max_x <= self.max_x + tol
            and other.max_y <= self.max_y + tol
        )

    def contains_disc(self, center: Point, radius: float, tol: float = EPS) -> bool:
        return self.inflate(-radius).contains_point(center, tol)

    def overlaps_rect(self, other: Rect, tol: float = EPS) -> bool:
        """True when the interiors intersect by more than ``tol`` (touching is not overlap)."""
        return (
            min(self.max_x, other.max_x) - max(self.min_x, other.min_x) > tol
            and min(self.max_y, other.max_y) - max(self.min_y, other.min_y) > tol
        )

    def distance_to_point(self, p: Point) -> float:
        """Euclidean distance from ``p`` to the rectangle (0 inside)."""
        dx = max(self.min_x - p[0], 0.0, p[0] - self.max_x)
        dy = max(self.min_y - p[1], 0.0, p[1] - self.max_y)
        return math.hypot(dx, dy)

    def overlaps_disc(self, center: Point, radius: float, tol: float = EPS) -> bool:
        """True when the disc reaches into the rectangle by more than ``tol``."""
        return self.distance_to_point(center) < radius - tol


def discs_overlap(c1: Point, r1: float, c2: Point, r2: float, tol: float = EPS) -> bool:
    """True when two discs overlap by more than ``tol``."""
    return math.dist(c1, c2) < r1 + r2 - tol


def segment_intersects_rect(p: Point, q: Point, rect: Rect, tol: float = EPS) -> bool:
    """True when the segment ``p``-``q`` passes through the interior of ``rect``.

    Liang-Barsky clipping against the rectangle shrunk by ``tol``, so that a segment
    that only grazes an edge does not count.
    """
    inner = rect.inflate(-tol)
    return inner.is_proper and _clip(p, q[0] - p[0], q[1] - p[1], inner) is not None


def segment_point_distance(p: Point, q: Point, c: Point) -> float:
    """Distance from point ``c`` to the segment ``p``-``q``."""
    dx, dy = q[0] - p[0], q[1] - p[1]
    length_sq = dx * dx + dy * dy
    t = 0.0 if length_sq == 0 else max(0.0, min(1.0, ((c[0] - p[0]) * dx + (c[1] - p[1]) * dy) / length_sq))
    return math.hypot(p[0] + t * dx - c[0], p[1] + t * dy - c[1])


def segment_rect_distance(p: Point, q: Point, rect: Rect) -> float:
    """Smallest distance between the segment ``p``-``q`` and ``rect`` (0 if they meet)."""
    if segment_intersects_rect(p, q, rect, tol=0.0) or rect.contains_point(p) or rect.contains_point(q):
        return 0.0
    corners = ((rect.min_x, rect.min_y), (rect.max_x, rect.min_y), (rect.max_x, rect.max_y), (rect.min_x, rect.max_y))
    edges = zip(corners, corners[1:] + corners[:1], strict=True)
    from_corners = min(segment_point_distance(p, q, c) for c in corners)
    from_ends = min(segment_point_distance(a, b, e) for a, b in edges for e in (p, q))
    return min(from_corners, from_ends)


def first_contact(p: Point, q: Point, radius: float, rects: Iterable[Rect]) -> float:
    """How far a disc of ``radius`` can slide from ``p`` towards ``q`` before it touches a rectangle.

    Returns the fraction ``t`` in [0, 1] of the segment that is free: 1.0 when the
    whole move is clear, 0.0 when the disc already touches something at ``p``. Exact
    (a swept-disc test against each rectangle's rounded Minkowski sum), so nothing
    tunnels, whatever the length of the move.
    """
    t_free = 1.0
    for rect in rects:
        t_free = min(t_free, _sweep_disc_rect(p, q, radius, rect))
        if t_free <= 0.0:
            return 0.0
    return t_free


def _sweep_disc_rect(p: Point, q: Point, radius: float, rect: Rect) -> float:
    """First ``t`` at which a disc moving ``p`` -> ``q`` touches ``rect`` (1.0 if never)."""
    if rect.distance_to_point(p) < radius - EPS:
        return 0.0
    dx, dy = q[0] - p[0], q[1] - p[1]
    hits: list[float] = []
    # The two "cross" rectangles of the Minkowski sum (the rectangle grown along one axis).
    for grown in (
        Rect(rect.min_x - radius, rect.min_y, rect.max_x + radius, rect.max_y),
        Rect(rect.min_x, rect.min_y - radius, rect.max_x, rect.max_y + radius),
    ):
        t = _ray_rect_entry(p, dx, dy, grown)
        if t is not None:
            hits.append(t)
    # The four rounded corners.
    for corner in (
        (rect.min_x, rect.min_y),
        (rect.max_x, rect.min_y),
        (rect.max_x, rect.max_y),
        (rect.min_x, rect.max_y),
    ):
        t = _ray_circle_entry(p, dx, dy, corner, radius)
        if t is not None:
            hits.append(t)
    return min([1.0, *hits])


def _clip(p: Point, dx: float, dy: float, rect: Rect) -> tuple[float, float] | None:
    """Liang-Barsky: the parameters ``(t0, t1)`` in [0, 1] of ``p + t (dx, dy)`` inside ``rect``, or None."""
    t0, t1 = 0.0, 1.0
    for denom, num in (
        (-dx, p[0] - rect.min_x),
        (dx, rect.max_x - p[0]),
        (-dy, p[1] - rect.min_y),
        (dy, rect.max_y - p[1]),
    ):
        if abs(denom) <= 1e-15:
            if num < 0:
                return None
            continue
        t = num / denom
        if denom < 0:
            t0 = max(t0, t)
        else:
            t1 = min(t1, t)
        if t0 > t1:
            return None
    return (t0, t1)


def _ray_rect_entry(p: Point, dx: float, dy: float, rect: Rect) -> float | None:
    """Entry parameter in [0, 1] of ``p + t (dx, dy)`` into ``rect``, or None."""
    span = _clip(p, dx, dy, rect)
    # Entering exactly at t0 = 0 with a direction that leaves the rectangle is not a hit.
    return span[0] if span is not None and span[1] - span[0] > EPS else None


def _ray_circle_entry(p: Point, dx: float, dy: float, c: Point, r: float) -> float | None:
    """Entry parameter in [0, 1] of ``p + t (dx, dy)`` into the circle ``(c, r)``, or None."""
    fx, fy = p[0] - c[0], p[1] - c[1]
    a = dx * dx + dy * dy
    if a <= 1e-18:
        return None
    b = 2 * (fx * dx + fy * dy)
    cc = fx * fx + fy * fy - r * r
    disc = b * b - 4 * a * cc
    if disc <= 0:
        return None
    sqrt_disc = math.sqrt(disc)
    t_in, t_out = (-b - sqrt_disc) / (2 * a), (-b + sqrt_disc) / (2 * a)
    if t_out <= EPS or t_in > 1.0:
        return None
    return max(t_in, 0.0)


def rect_under(center: Point, radius: float, surfaces: Iterable[Rect]) -> int | None:
    """Index of the first surface that holds the whole disc ``(center, radius)``, or None."""
    for index, surface in enumerate(surfaces):
        if surface.contains_disc(center, radius, tol=1e-6):
            return index
    return None
