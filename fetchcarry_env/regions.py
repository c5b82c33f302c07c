"""The regions around a rectangle that the motion and arm rules test: one implementation for the env and the planner.

Around every table and obstacle grown by the base radius ``r`` lie eight overlapping
*move regions* (the MILP expert's Eq. 18, ``docs/formulation.md``, "Collision model"):
the four sides of the grown rectangle (``x >= max_x + r``, ``x <= min_x - r``,
``y >= max_y + r``, ``y <= min_y - r``) and the free sides of its four corners cut by
the 45-degree tangents of the rounded corners (``su x + sv y >= su cx + sv cy + r sqrt(2)``
at corner ``(cx, cy)`` with outward signs ``(su, sv)``), i.e. the outside of an
*octagon* that holds the disc-swept rectangle and touches it. A move is allowed when
both its ends lie in one common region of every such octagon: the segment then stays
in a half-plane the disc's centre may not leave, so the swept disc is clear.

The arm rule (Eq. 19) uses the four *side half-planes* of a rectangle itself
(``x >= max_x``, ...): the base and the hand lie in one common side.

Lattice points (``origin + (i, j) * resolution``, :class:`~fetchcarry_env.actions.Lattice`)
are tested in lattice-index units with exact integer bounds: "``x >= U``" becomes
"``i >= ceil((U - origin) / resolution)``", rounded inwards with :data:`GEOM_TOL`, so a
lattice point satisfies the rounded bound exactly when it satisfies the metric one (up
to that tolerance). Points off the lattice (the start, the base after a jammed push) are
tested in metres with the same tolerance. Hand points are tested in metres with
:data:`HAND_TOL`. Everything here is pure geometry; the env (:mod:`fetchcarry_env.rules`)
and the planner (``expert.milp.grid``, ``expert.milp.options``) both build on it.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import Heading, Point, Rect, to_world_frame
from fetchcarry_env.kinematics import hand_offset
from fetchcarry_env.scenario import Posture

GEOM_TOL = 5e-7  # metres: this close outside an exact bound counts as inside (covers float32 observations)
HAND_TOL = 5e-7  # metres: a hand point this close to a side half-plane counts as inside (float32 observations)
ON_LATTICE_TOL = 1e-9  # metres: a base this close to a lattice point is that lattice point (float noise of a stroke)

SIDES = ("+x", "-x", "+y", "-y")
"""The order of the four sides: ``x >= max_x``, ``x <= min_x``, ``y >= max_y``, ``y <= min_y`` (grown by a margin)."""
CORNERS: tuple[tuple[int, int], ...] = ((1, 1), (-1, 1), (-1, -1), (1, -1))
"""Outward signs ``(su, sv)`` of the corners in the octagon's order: NE, NW, SW, SE."""
REGIONS = len(SIDES) + len(CORNERS)  # the octagon's eight move regions: the four sides, then the four corner cuts


# ---------------------------------------------------------------------- planes in lattice indices
@dataclass(frozen=True)
class HalfPlane:
    """``index <= bound`` (``upper``) or ``index >= bound`` on ``axis`` (0: x, 1: y), in lattice indices."""

    axis: int
    upper: bool
    bound: int

    def shifted(self, cells: int) -> HalfPlane:
        """The condition on ``p`` that ``p + cells`` (along this axis) satisfies this half-plane."""
        return HalfPlane(self.axis, self.upper, self.bound - cells)

    def tighter(self, other: HalfPlane) -> HalfPlane:
        """The intersection of two half-planes of the same axis and sense."""
        assert (self.axis, self.upper) == (other.axis, other.upper)
        return HalfPlane(
            self.axis, self.upper, min(self.bound, other.bound) if self.upper else max(self.bound, other.bound)
        )

    def holds(self, index: float) -> bool:
        return index <= self.bound if self.upper else index >= self.bound

    @property
    def row(self) -> tuple[int, int, int]:
        """``(a, b, c)`` with the half-plane written ``a * i + b * j >= c``."""
        a, b = (1, 0) if self.axis == 0 else (0, 1)
        return (-a, -b, -self.bound) if self.upper else (a, b, self.bound)


@dataclass(frozen=True)
class DiagonalPlane:
    """``su * i + sv * j >= bound`` (``su``, ``sv`` non-zero whole numbers), in lattice indices: a cut corner.

    ``(1, 1)``-type planes are the octagon's 45-degree cuts; other directions (``(2, 1)``,
    ``(1, 2)``, ...) are further tangents of the rounded corner (the planner's finer corners).
    """

    su: int
    sv: int
    bound: int

    def value_range(self, box: IndexBox) -> tuple[int, int]:
        """The least and the largest ``su * i + sv * j`` over the (non-empty) ``box``."""
        i_lo, i_hi = sorted((self.su * box.i_lo, self.su * box.i_hi))
        j_lo, j_hi = sorted((self.sv * box.j_lo, self.sv * box.j_hi))
        return i_lo + j_lo, i_hi + j_hi

    @property
    def octilinear(self) -> bool:
        """Whether the plane is one of the octagon's 45-degree cuts (``|su| = |sv| = 1``)."""
        return abs(self.su) == 1 and abs(self.sv) == 1

    def holds_at(self, i: float, j: float) -> bool:
        return self.su * i + self.sv * j >= self.bound

    @property
    def row(self) -> tuple[int, int, int]:
        """``(a, b, c)`` with the plane written ``a * i + b * j >= c``."""
        return (self.su, self.sv, self.bound)


Plane = HalfPlane | DiagonalPlane


@dataclass(frozen=True)
class IndexBox:
    """Lattice points ``i_lo <= i <= i_hi``, ``j_lo <= j <= j_hi`` (empty when a range is)."""

    i_lo: int
    i_hi: int
    j_lo: int
    j_hi: int

    @property
    def empty(self) -> bool:
        return self.i_lo > self.i_hi or self.j_lo > self.j_hi

    def lo(self, axis: int) -> int:
        return self.i_lo if axis == 0 else self.j_lo

    def hi(self, axis: int) -> int:
        return self.i_hi if axis == 0 else self.j_hi

    def intersect(self, other: IndexBox) -> IndexBox:
        return IndexBox(
            max(self.i_lo, other.i_lo),
            min(self.i_hi, other.i_hi),
            max(self.j_lo, other.j_lo),
            min(self.j_hi, other.j_hi),
        )

    def clip(self, plane: Plane) -> IndexBox:
        """The part of the box inside ``plane`` (for a diagonal plane: the bounding box of that part)."""
        i_lo, i_hi, j_lo, j_hi = self.i_lo, self.i_hi, self.j_lo, self.j_hi
        if isinstance(plane, DiagonalPlane):
            if self.empty:
                return self
            # su * i >= bound - sv * j: the loosest j gives the bounding box's limit on i, and vice versa.
            j_best = max(plane.sv * j_lo, plane.sv * j_hi)
            i_best = max(plane.su * i_lo, plane.su * i_hi)
            i_need, j_need = plane.bound - j_best, plane.bound - i_best  # su * i >= i_need, sv * j >= j_need
            if plane.su > 0:
                i_lo = max(i_lo, -(-i_need // plane.su))
            else:
                i_hi = min(i_hi, i_need // plane.su)
            if plane.sv > 0:
                j_lo = max(j_lo, -(-j_need // plane.sv))
            else:
                j_hi = min(j_hi, j_need // plane.sv)
            return IndexBox(i_lo, i_hi, j_lo, j_hi)
        if plane.axis == 0:
            i_lo, i_hi = (i_lo, min(i_hi, plane.bound)) if plane.upper else (max(i_lo, plane.bound), i_hi)
        else:
            j_lo, j_hi = (j_lo, min(j_hi, plane.bound)) if plane.upper else (max(j_lo, plane.bound), j_hi)
        return IndexBox(i_lo, i_hi, j_lo, j_hi)

    def inside(self, plane: Plane) -> bool:
        """True when the whole (non-empty) box lies in ``plane``."""
        if isinstance(plane, DiagonalPlane):
            return plane.value_range(self)[0] >= plane.bound
        return plane.holds(self.hi(plane.axis)) if plane.upper else plane.holds(self.lo(plane.axis))

    def meets(self, plane: Plane) -> bool:
        """True when some point of the box lies in ``plane``."""
        if self.empty:
            return False
        if isinstance(plane, DiagonalPlane):
            return plane.value_range(self)[1] >= plane.bound
        return self.lo(plane.axis) <= plane.bound if plane.upper else self.hi(plane.axis) >= plane.bound

    def shifted(self, di: int, dj: int) -> IndexBox:
        return IndexBox(self.i_lo + di, self.i_hi + di, self.j_lo + dj, self.j_hi + dj)

    def contains(self, i: int, j: int) -> bool:
        return self.i_lo <= i <= self.i_hi and self.j_lo <= j <= self.j_hi


# ---------------------------------------------------------------------- exact metres -> index rounding
def index_of(lattice: Lattice, axis: int, value: float) -> float:
    """``value`` (metres) in index units along ``axis`` (not rounded)."""
    return (value - lattice.origin[axis]) / lattice.resolution


def index_at_most(lattice: Lattice, axis: int, value: float) -> int:
    """The largest lattice index whose coordinate is ``<= value`` (metres, with :data:`GEOM_TOL`)."""
    return math.floor(index_of(lattice, axis, value + GEOM_TOL) + 1e-12)


def index_at_least(lattice: Lattice, axis: int, value: float) -> int:
    """The smallest lattice index whose coordinate is ``>= value`` (metres, with :data:`GEOM_TOL`)."""
    return math.ceil(index_of(lattice, axis, value - GEOM_TOL) - 1e-12)


def at_most(lattice: Lattice, axis: int, value: float) -> HalfPlane:
    """The half-plane of lattice points with coordinate ``<= value`` (metres) on ``axis``."""
    return HalfPlane(axis, True, index_at_most(lattice, axis, value))


def at_least(lattice: Lattice, axis: int, value: float) -> HalfPlane:
    """The half-plane of lattice points with coordinate ``>= value`` (metres) on ``axis``."""
    return HalfPlane(axis, False, index_at_least(lattice, axis, value))


def diagonal_at_least(lattice: Lattice, su: int, sv: int, value: float) -> DiagonalPlane:
    """The lattice points with ``su * x + sv * y >= value`` (metres)."""
    origin = lattice.origin
    scaled = (value - su * origin[0] - sv * origin[1] - GEOM_TOL) / lattice.resolution
    return DiagonalPlane(su, sv, math.ceil(scaled - 1e-12))


def area_domain(lattice: Lattice, area: Rect, radius: float) -> IndexBox:
    """The lattice points at which a disc of ``radius`` lies inside ``area`` (the area shrunk by it, Eq. 27)."""
    inner = area.inflate(-radius)
    return IndexBox(
        max(0, index_at_least(lattice, 0, inner.min_x)),
        min(lattice.shape[0] - 1, index_at_most(lattice, 0, inner.max_x)),
        max(0, index_at_least(lattice, 1, inner.min_y)),
        min(lattice.shape[1] - 1, index_at_most(lattice, 1, inner.max_y)),
    )


def lattice_cell(lattice: Lattice | None, point: Point) -> tuple[int, int] | None:
    """The lattice point that ``point`` is (within :data:`ON_LATTICE_TOL` per coordinate), or None.

    Without a lattice (None) no point is a lattice point: every test is then in metres,
    and stricter than the index test by at most float noise (the index bounds keep
    1e-12 cell of slack), so it never allows what the index test refuses.
    """
    if lattice is None:
        return None
    (ox, oy), res, (nx, ny) = lattice.origin, lattice.resolution, lattice.shape
    i, j = round((point[0] - ox) / res), round((point[1] - oy) / res)
    if not (0 <= i < nx and 0 <= j < ny):
        return None
    x, y = lattice.point(i, j)
    if abs(x - point[0]) > ON_LATTICE_TOL or abs(y - point[1]) > ON_LATTICE_TOL:
        return None
    return (i, j)


def box_between(lattice: Lattice, lo: Point, hi: Point) -> IndexBox:
    """Lattice points inside the box ``[lo, hi]`` (inclusive, metres, with :data:`GEOM_TOL`)."""
    return IndexBox(
        index_at_least(lattice, 0, lo[0]),
        index_at_most(lattice, 0, hi[0]),
        index_at_least(lattice, 1, lo[1]),
        index_at_most(lattice, 1, hi[1]),
    )


# ---------------------------------------------------------------------- the arm's reach
def reach_box(lattice: Lattice, hand: Point, heading: Heading, posture: Posture, margin: float = 0.0) -> IndexBox:
    """Lattice points from which ``posture`` at ``heading`` puts the hand on ``hand`` (ranges widened by ``margin``)."""
    offsets = [to_world_frame(heading, f, lat) for f in posture.forward for lat in posture.lateral]
    dxs, dys = [o[0] for o in offsets], [o[1] for o in offsets]
    return box_between(
        lattice,
        (hand[0] - max(dxs) - margin, hand[1] - max(dys) - margin),
        (hand[0] - min(dxs) + margin, hand[1] - min(dys) + margin),
    )


def in_reach(lattice: Lattice | None, base: Point, heading: Heading, posture: Posture, point: Point) -> bool:
    """Whether ``posture`` at ``heading`` puts the hand over ``point`` from a base at ``base`` (the planner's reach).

    A lattice base is tested against :func:`reach_box` (the posture's exact ranges rounded
    to the lattice with :data:`GEOM_TOL`), another base by its robot-frame offset, the
    ranges widened by :data:`GEOM_TOL` (metres).
    """
    cell = lattice_cell(lattice, base)
    if cell is not None:
        return reach_box(lattice, point, heading, posture).contains(*cell)
    return posture.reaches(*hand_offset(base, heading, point), tol=GEOM_TOL)


# ---------------------------------------------------------------------- a rectangle's regions
def side_regions(lattice: Lattice, rect: Rect, margin: float) -> tuple[HalfPlane, HalfPlane, HalfPlane, HalfPlane]:
    """The four sides of ``rect`` grown by ``margin`` as lattice half-planes, in :data:`SIDES` order.

    With the base radius as the margin: the paper's regions ``R_{j,1..4}`` (Fig. 2); with 0: the arm rule's sides.
    """
    return (
        at_least(lattice, 0, rect.max_x + margin),
        at_most(lattice, 0, rect.min_x - margin),
        at_least(lattice, 1, rect.max_y + margin),
        at_most(lattice, 1, rect.min_y - margin),
    )


def tangent_value(rect: Rect, radius: float, a: int, b: int) -> float:
    """``a cx + b cy + radius |(a, b)|`` at the corner ``(cx, cy)`` the normal ``(a, b)`` points from (metres)."""
    cx = rect.max_x if a > 0 else rect.min_x
    cy = rect.max_y if b > 0 else rect.min_y
    return a * cx + b * cy + radius * math.hypot(a, b)


def corner_cut(lattice: Lattice, rect: Rect, radius: float, a: int, b: int) -> DiagonalPlane:
    """The lattice points beyond the tangent with normal ``(a, b)`` of ``rect``'s corner rounded by ``radius``."""
    return diagonal_at_least(lattice, a, b, tangent_value(rect, radius, a, b))


@functools.lru_cache(maxsize=4096)
def octagon_regions(lattice: Lattice, rect: Rect, radius: float) -> tuple[Plane, ...]:
    """The eight move regions of ``rect`` grown by ``radius``: :func:`side_regions`, then the :data:`CORNERS` cuts."""
    cuts = tuple(corner_cut(lattice, rect, radius, su, sv) for su, sv in CORNERS)
    return (*side_regions(lattice, rect, radius), *cuts)


def point_in_side(point: Point, rect: Rect, margin: float, side: int) -> bool:
    """Exact test (metres, :data:`GEOM_TOL`) of an off-lattice point against side ``side`` of :func:`side_regions`."""
    x, y = point
    return (
        x >= rect.max_x + margin - GEOM_TOL,
        x <= rect.min_x - margin + GEOM_TOL,
        y >= rect.max_y + margin - GEOM_TOL,
        y <= rect.min_y - margin + GEOM_TOL,
    )[side]


def point_beyond_tangent(point: Point, rect: Rect, radius: float, a: int, b: int) -> bool:
    """Exact test (metres, :data:`GEOM_TOL`) of an off-lattice point against the corner cut of :func:`corner_cut`."""
    return a * point[0] + b * point[1] >= tangent_value(rect, radius, a, b) - GEOM_TOL


def point_in_octagon_region(point: Point, rect: Rect, radius: float, region: int) -> bool:
    """Exact test of an off-lattice point against region ``region`` of :func:`octagon_regions`."""
    if region < len(SIDES):
        return point_in_side(point, rect, radius, region)
    su, sv = CORNERS[region - len(SIDES)]
    return point_beyond_tangent(point, rect, radius, su, sv)


def hand_in_side(rect: Rect, hand: Point, side: int) -> bool:
    """Whether the hand point lies in side ``side`` (:data:`SIDES` order) of ``rect`` itself (:data:`HAND_TOL`)."""
    x, y = hand
    return (
        x >= rect.max_x - HAND_TOL,
        x <= rect.min_x + HAND_TOL,
        y >= rect.max_y - HAND_TOL,
        y <= rect.min_y + HAND_TOL,
    )[side]


# ---------------------------------------------------------------------- which regions hold a point
ALL_SIDES = (1 << len(SIDES)) - 1  # the bits of the four sides in an octagon's region bits


@functools.lru_cache(maxsize=4096)
def octagon_rows(lattice: Lattice, rect: Rect, radius: float) -> tuple[tuple[int, int, int], ...]:
    """:func:`octagon_regions` as rows ``(a, b, c)``, each region written ``a * i + b * j >= c``."""
    return tuple(plane.row for plane in octagon_regions(lattice, rect, radius))


def side_rows(lattice: Lattice, rect: Rect) -> tuple[tuple[int, int, int], ...]:
    """The side half-planes of ``rect`` itself (margin 0, the arm rule's) as rows ``(a, b, c)``."""
    return tuple(plane.row for plane in side_regions(lattice, rect, 0.0))


def row_bits(rows: Sequence[tuple[int, int, int]], cell: tuple[int, int]) -> int:
    """Bit ``n`` set when lattice point ``cell`` lies in the plane of ``rows[n]`` (exact integers)."""
    i, j = cell
    return sum(1 << n for n, (a, b, c) in enumerate(rows) if a * i + b * j >= c)


def octagon_bits(lattice: Lattice | None, rect: Rect, radius: float, point: Point) -> int:
    """The move regions of ``rect`` that hold a base at ``point``, as bits (:data:`REGIONS` of them).

    A lattice point (:func:`lattice_cell`) is tested in lattice indices, another point in metres.
    """
    cell = lattice_cell(lattice, point)
    if cell is not None:
        return row_bits(octagon_rows(lattice, rect, radius), cell)
    return sum(1 << n for n in range(REGIONS) if point_in_octagon_region(point, rect, radius, n))


def side_bits(lattice: Lattice | None, rect: Rect, point: Point) -> int:
    """The side half-planes of ``rect`` itself that hold a base at ``point`` (the arm rule), as bits."""
    cell = lattice_cell(lattice, point)
    if cell is not None:
        return row_bits(side_rows(lattice, rect), cell)
    return sum(1 << n for n in range(len(SIDES)) if point_in_side(point, rect, 0.0, n))


def hand_bits(rect: Rect, hand: Point) -> int:
    """The side half-planes of ``rect`` that hold the hand point (:func:`hand_in_side`), as bits."""
    return sum(1 << n for n in range(len(SIDES)) if hand_in_side(rect, hand, n))


# ---------------------------------------------------------------------- many lattice points at once
def cells_bits(rows: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """``(N, R)`` uint8: :func:`row_bits` of lattice points ``(i[n], j[n])`` for each of ``R`` sets of rows.

    ``rows`` is ``(R, P, 3)`` int64 (at most 8 planes a set); exact integer arithmetic.
    """
    i = np.asarray(i, dtype=np.int64)[:, None, None]
    j = np.asarray(j, dtype=np.int64)[:, None, None]
    inside = rows[None, :, :, 0] * i + rows[None, :, :, 1] * j >= rows[None, :, :, 2]  # (N, R, P)
    weights = (1 << np.arange(rows.shape[1], dtype=np.int64)).astype(np.uint8)
    return (inside.astype(np.uint8) * weights).sum(axis=2, dtype=np.uint8)


def hands_bits(rects: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``(N, R)`` uint8: :func:`hand_bits` of hand points ``(x[n], y[n])`` (metres) against rectangles ``(R, 4)``.

    The scalar test's comparisons, elementwise: ``x >= max_x - HAND_TOL`` and so on.
    """
    x, y = np.asarray(x, dtype=float)[:, None], np.asarray(y, dtype=float)[:, None]
    x0, y0, x1, y1 = (rects[None, :, k] for k in range(4))
    sides = (x >= x1 - HAND_TOL, x <= x0 + HAND_TOL, y >= y1 - HAND_TOL, y <= y0 + HAND_TOL)
    return sum(side.astype(np.uint8) << n for n, side in enumerate(sides)).astype(np.uint8)


def grid_bits(rows: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """``(nx, ny, R)`` uint8: :func:`row_bits` of every point of a lattice of ``shape``, for each set of ``rows``.

    ``rows`` is ``(R, P, 3)`` int64 (at most 8 planes a set); one exact integer pass per plane.
    """
    i = np.arange(shape[0], dtype=np.int64)[:, None]
    j = np.arange(shape[1], dtype=np.int64)[None, :]
    out = np.zeros((*shape, rows.shape[0]), dtype=np.uint8)
    for r, planes in enumerate(rows.tolist()):
        for n, (a, b, c) in enumerate(planes):
            out[:, :, r] |= (a * i + b * j >= c).astype(np.uint8) << n
    return out
