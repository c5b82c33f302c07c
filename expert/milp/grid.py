"""The action lattice seen by the MILP: base positions in lattice-index units, boxes and half-planes.

The environment sends the base to lattice points ``origin + (i, j) * resolution``
(:class:`fetchcarry_env.actions.Lattice`). The MILP keeps every base coordinate of a
phase after the start in *index units* (``u = (x - origin_x) / resolution``), and
every geometric condition on a base (reach, the free side of a table, the area) is
rounded inwards to the lattice *exactly*: "``x <= U``" becomes "``i <= floor((U - origin) /
resolution)``". A base that satisfies the rounded condition, snapped to its nearest
lattice point, satisfies the exact one. This is ``docs/design.md``'s "inflate by half a
cell" made exact: the half-cell margin is never more than needed (see
``docs/formulation.md``, "Lattice agreement").

In the MILP a rounded bound ``i <= a`` is written ``u <= a + 1/2 - EPS_CELL`` when the
base coordinates are continuous (then rounding to the nearest point is unambiguous)
and ``u <= a`` when they are integer (the default, so no snapping is needed at all).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from fetchcarry_env import regions
from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import Point, Rect
from fetchcarry_env.regions import (
    DiagonalPlane,
    HalfPlane,
    IndexBox,
    Plane,
    point_beyond_tangent,
    point_in_side,
    side_regions,
)

EPS_CELL = 1e-3  # cells: keeps continuous coordinates this far from a rounding tie


@dataclass(frozen=True)
class Grid:
    """The lattice, the base domain (the area's Eq. 27 bounds) and how bounds are written in the MILP.

    ``integral``: base coordinates are integer lattice indices (exact, no snapping) or
    continuous ones snapped to the nearest point afterwards.
    """

    lattice: Lattice
    domain: IndexBox
    integral: bool = True
    corner_detail: int = 1  # the corner tangents of Eq. 18: corner_directions(corner_detail)
    first_move_tangents: bool = False  # the first move also gets the start's tangents (start_tangents)
    # Further corner tangents per rectangle, (rect, normals): the directions seen from pose points (pose_normals).
    extra_normals: tuple[tuple[Rect, tuple[tuple[int, int], ...]], ...] = ()

    @classmethod
    def for_area(
        cls,
        lattice: Lattice,
        area: Rect,
        radius: float,
        integral: bool = True,
        corner_detail: int = 1,
        first_move_tangents: bool = False,
    ) -> Grid:
        """The grid whose domain is every lattice point at which the base disc lies inside ``area`` (Eq. 27)."""
        domain = regions.area_domain(lattice, area, radius)
        return cls(lattice, domain, integral, corner_detail, first_move_tangents)

    @property
    def resolution(self) -> float:
        return self.lattice.resolution

    # ------------------------------------------------------------ exact world -> index rounding
    def index_of(self, axis: int, value: float) -> float:
        """``value`` (metres) in index units along ``axis`` (not rounded)."""
        return regions.index_of(self.lattice, axis, value)

    def index_at_most(self, axis: int, value: float) -> int:
        """The largest lattice index whose coordinate is ``<= value`` (metres)."""
        return regions.index_at_most(self.lattice, axis, value)

    def index_at_least(self, axis: int, value: float) -> int:
        """The smallest lattice index whose coordinate is ``>= value`` (metres)."""
        return regions.index_at_least(self.lattice, axis, value)

    def at_most(self, axis: int, value: float) -> HalfPlane:
        """The half-plane of lattice points with coordinate ``<= value`` on ``axis``."""
        return regions.at_most(self.lattice, axis, value)

    def at_least(self, axis: int, value: float) -> HalfPlane:
        return regions.at_least(self.lattice, axis, value)

    def box_between(self, lo: Point, hi: Point) -> IndexBox:
        """Lattice points inside the world box ``[lo, hi]`` (inclusive, metres)."""
        return regions.box_between(self.lattice, lo, hi)

    def point(self, i: int, j: int) -> Point:
        return self.lattice.point(i, j)

    # ------------------------------------------------------------ how the MILP writes bounds
    def upper(self, bound: int) -> float:
        """Right-hand side, in index units, of the MILP bound for ``index <= bound``."""
        return float(bound) if self.integral else bound + 0.5 - EPS_CELL

    def lower(self, bound: int) -> float:
        """Right-hand side, in index units, of the MILP bound for ``index >= bound``."""
        return float(bound) if self.integral else bound - 0.5 + EPS_CELL

    def rhs(self, plane: Plane) -> float:
        """Right-hand side of the MILP row for ``plane`` (a diagonal plane reads ``su u + sv v >= rhs``)."""
        if isinstance(plane, DiagonalPlane):
            # Continuous u, v each move by less than 1/2 when snapped: su u + sv v by less than (|su| + |sv|) / 2.
            weight = abs(plane.su) + abs(plane.sv)
            return float(plane.bound) if self.integral else plane.bound + weight * (0.5 - EPS_CELL)
        return self.upper(plane.bound) if plane.upper else self.lower(plane.bound)

    def diagonal_at_least(self, su: int, sv: int, value: float) -> DiagonalPlane:
        """The lattice points with ``su * x + sv * y >= value`` (metres)."""
        return regions.diagonal_at_least(self.lattice, su, sv, value)

    def plane_value_range(self, plane: DiagonalPlane) -> tuple[float, float]:
        """The least and largest ``su u + sv v`` (index units) of MILP base variables over the domain."""
        lo, hi = plane.value_range(self.domain)
        slack = (abs(plane.su) + abs(plane.sv)) / 2
        return (float(lo), float(hi)) if self.integral else (lo - slack, hi + slack)

    def var_bounds(self, axis: int) -> tuple[float, float]:
        """Bounds (index units) of a base coordinate variable: the domain on ``axis``."""
        return self.lower(self.domain.lo(axis)), self.upper(self.domain.hi(axis))


# ---------------------------------------------------------------------- rectangle regions
def base_regions(grid: Grid, rect: Rect, margin: float) -> tuple[HalfPlane, ...]:
    """The paper's four regions R_{j,1..4} of Fig. 2 around ``rect`` grown by ``margin``, for lattice bases.

    Order: +x side (x >= max_x + margin), -x side, +y side, -y side (:func:`fetchcarry_env.regions.side_regions`).
    """
    return side_regions(grid.lattice, rect, margin)


SQRT2 = math.sqrt(2.0)
CORNERS = regions.CORNERS  # outward signs of the corners: NE, NW, SW, SE
MAX_CORNER_DETAIL = 6  # the largest corner_detail accepted (11 tangents a corner at 4; 6 gives 23)


@functools.cache
def corner_directions(detail: int) -> tuple[tuple[int, int], ...]:
    """Normals ``(a, b)`` (NE quadrant) of the tangents cut at every corner: coprime ``1 <= a, b <= detail``.

    ``detail = 1`` gives ``(1, 1)`` alone, the octagon; 2 adds ``(2, 1), (1, 2)`` (a 16-gon),
    3 a 32-gon, 4 a 48-gon (``docs/formulation.md``, "Collision model", measures them).
    Ordered by angle. Mirrored to each corner.
    """
    pairs = {(a, b) for a in range(1, detail + 1) for b in range(1, detail + 1) if math.gcd(a, b) == 1}
    return tuple(sorted(pairs, key=lambda p: math.atan2(p[1], p[0])))


@functools.cache
def corner_normals(detail: int) -> tuple[tuple[int, int], ...]:
    """The normals ``(su * a, sv * b)`` of the corner tangents, per corner (NE, NW, SW, SE), as in move_regions."""
    return tuple((su * a, sv * b) for su, sv in CORNERS for a, b in corner_directions(detail))


def rect_normals(grid: Grid, rect: Rect) -> tuple[tuple[int, int], ...]:
    """The normals of ``rect``'s corner tangents: :func:`corner_normals` and the grid's ``extra_normals`` for it."""
    extra = next((normals for r, normals in grid.extra_normals if r == rect), ())
    regular = corner_normals(grid.corner_detail)
    return regular + tuple(n for n in extra if n not in regular)


def move_regions(grid: Grid, rect: Rect, radius: float) -> tuple[Plane, ...]:
    """The regions of Eq. 18 in our tighter model: outside a polygon around ``rect`` grown by ``radius``.

    The first four are :func:`base_regions` (the sides of the grown rectangle); the
    others cut its corners, one per normal of :func:`rect_normals` (by default those of
    :func:`corner_directions`, ``grid.corner_detail``, NE, NW, SW, SE):
    ``a x + b y >= a cx + b cy + radius |(a, b)|`` at corner ``(cx, cy)``, the tangent to
    the corner's quarter circle with that normal. With ``((1, 1),)`` (the octagon) the
    cut is at 45 degrees. The polygon holds the rectangle's disc-swept shape (every point
    outside it is ``radius`` or more from ``rect``) and touches it on every side. With the
    default ``corner_detail`` and no extra normals these are exactly the env's regions,
    :func:`fetchcarry_env.regions.octagon_regions`.
    """
    out: list[Plane] = list(base_regions(grid, rect, radius))
    for a, b in rect_normals(grid, rect):
        out.append(regions.corner_cut(grid.lattice, rect, radius, a, b))
    return tuple(out)


START_TANGENT_COEFFICIENT = 1000  # the largest whole coefficient of a start tangent's normal
START_TANGENT_SLACK = 1e-5  # metres: a start tangent keeps at least this between its line and the grown rectangle


@functools.lru_cache(maxsize=65536)
def start_tangents(grid: Grid, point: Point, rect: Rect, radius: float) -> tuple[DiagonalPlane, ...]:
    """The lines through the exact start ``point`` that (nearly) touch ``rect`` grown by ``radius``, as regions.

    Each is ``a i + b j >= c`` with whole ``a``, ``b`` (a normal within a hair of the
    tangent's, turned 3 mrad away from the rectangle so that the line separates it from the
    disc by at least :data:`START_TANGENT_SLACK`) through ``point``: a move from the start
    to a lattice point on the far side clears the rectangle (the segment stays in the
    half-plane). They make the first move exact (up to that turn) where it passes a corner
    at any angle, and hold only for moves from ``point``. Empty when ``point`` is inside the
    grown rectangle; an axis-parallel tangent is left out (a side of the rectangle covers it).
    """
    corners = [(x, y) for x in (rect.min_x, rect.max_x) for y in (rect.min_y, rect.max_y)]
    px, py = point

    def slack(theta: float) -> float:
        nx, ny = math.cos(theta), math.sin(theta)
        return nx * px + ny * py - max(nx * cx + ny * cy for cx, cy in corners) - radius

    thetas = np.linspace(0.0, 2 * math.pi, 720, endpoint=False)
    nx, ny = np.cos(thetas), np.sin(thetas)
    support = np.max(np.stack([nx * cx + ny * cy for cx, cy in corners]), axis=0)
    ok = nx * px + ny * py - support - radius > 0
    if ok.all() or not ok.any():
        return ()
    out = []
    for edge in np.flatnonzero(ok != np.roll(ok, 1)):  # ok changes between thetas[edge - 1] and thetas[edge]
        lo, hi = float(thetas[edge - 1]) - (2 * math.pi if edge == 0 else 0.0), float(thetas[edge])
        inside_hi = bool(ok[edge])
        for _ in range(40):
            mid = (lo + hi) / 2
            if (slack(mid) > 0) == inside_hi:
                hi = mid
            else:
                lo = mid
        theta = hi + 3e-3 if inside_hi else lo - 3e-3  # into the separating arc (radians)
        a, b = round(START_TANGENT_COEFFICIENT * math.cos(theta)), round(START_TANGENT_COEFFICIENT * math.sin(theta))
        if a == 0 or b == 0 or slack(math.atan2(b, a)) < START_TANGENT_SLACK:
            continue
        out.append(grid.diagonal_at_least(a, b, a * px + b * py))
    return tuple(out)


POSE_NORMAL_MERGE = 2e-3  # radians: a pose tangent this close in angle to one kept already is left out


def pose_normals(grid: Grid, points: Iterable[Point], rect: Rect, radius: float) -> tuple[tuple[int, int], ...]:
    """Corner tangent normals of ``rect`` seen from ``points`` (pose bases): those of :func:`start_tangents`.

    Each is the normal of a line through a point that separates it from ``rect`` grown by
    ``radius`` (turned 3 mrad into the point's side), so the tangent of ``rect``'s rounded
    corner with that normal (a region of :func:`move_regions`) holds the point: a move from
    the point to any lattice point beyond that tangent clears ``rect`` exactly. Normals
    within :data:`POSE_NORMAL_MERGE` of one kept (in angle) are left out (the kept one still
    holds the point: it is at least 1 mrad inside the point's side). Ordered by angle.
    """
    found = {(p.su, p.sv) for point in points for p in start_tangents(grid, point, rect, radius)}
    ordered = sorted(found, key=lambda n: math.atan2(n[1], n[0]))
    kept: list[tuple[int, int]] = []
    for normal in ordered:
        angle = math.atan2(normal[1], normal[0])
        if not kept or angle - math.atan2(kept[-1][1], kept[-1][0]) > POSE_NORMAL_MERGE:
            kept.append(normal)
    return tuple(kept)


def point_in_move_region(grid: Grid, point: Point, rect: Rect, radius: float, region: int) -> bool:
    """Exact test of an off-lattice point against region ``region`` of :func:`move_regions`."""
    if region < 4:
        return point_in_side(point, rect, radius, region)
    a, b = rect_normals(grid, rect)[region - 4]
    return point_beyond_tangent(point, rect, radius, a, b)


point_in_region = point_in_side  # exact test of an off-lattice point against a region of base_regions (same order)


# ---------------------------------------------------------------------- splitting boxes
@dataclass(frozen=True)
class Condition:
    """A disjunction of half-planes the base must satisfy; ``tag`` None: always, else only in that state."""

    planes: tuple[HalfPlane, ...]
    tag: object = None


def split_box(box: IndexBox, conditions: Iterable[Condition]) -> list[tuple[IndexBox, frozenset]]:
    """Cut ``box`` into boxes on which every condition is either met everywhere or nowhere.

    Cells that break an untagged condition are dropped; each remaining box comes with
    the set of tags whose conditions it breaks (the states in which it may not be
    used). Boxes with the same tag set are merged greedily into few rectangles.
    """
    if box.empty:
        return []
    partial: list[Condition] = []
    always_broken: set = set()
    for condition in conditions:
        if any(box.inside(p) for p in condition.planes):
            continue
        if not any(box.meets(p) for p in condition.planes):
            if condition.tag is None:
                return []
            always_broken.add(condition.tag)
            continue
        partial.append(condition)
    if not partial:
        return [(box, frozenset(always_broken))]
    cuts = _cuts(box, partial)
    groups: dict[frozenset, list[tuple[int, int]]] = {}
    for xi, (i_lo, i_hi) in enumerate(cuts[0]):
        for yi, (j_lo, j_hi) in enumerate(cuts[1]):
            cell = IndexBox(i_lo, i_hi, j_lo, j_hi)
            broken = set(always_broken)
            keep = True
            for condition in partial:
                if not any(cell.inside(p) for p in condition.planes):
                    if condition.tag is None:
                        keep = False
                        break
                    broken.add(condition.tag)
            if keep:
                groups.setdefault(frozenset(broken), []).append((xi, yi))
    out = []
    for tags, cells in groups.items():
        out.extend((merged, tags) for merged in _merge(cells, cuts))
    return out


def _cuts(box: IndexBox, conditions: Sequence[Condition]) -> tuple[list[tuple[int, int]], list[tuple[int, int]]]:
    """Per axis, the index intervals between every bound of the conditions' half-planes."""
    out = []
    for axis in (0, 1):
        lo, hi = box.lo(axis), box.hi(axis)
        starts = {lo}
        for condition in conditions:
            for plane in condition.planes:
                if plane.axis != axis:
                    continue
                start = plane.bound + 1 if plane.upper else plane.bound
                if lo < start <= hi:
                    starts.add(start)
        ordered = sorted(starts)
        out.append([(s, (ordered[n + 1] - 1) if n + 1 < len(ordered) else hi) for n, s in enumerate(ordered)])
    return out[0], out[1]


def _merge(cells: list[tuple[int, int]], cuts: tuple[list, list]) -> list[IndexBox]:
    """Greedy cover of grid cells by rectangles: vertical runs per column, then equal runs across columns."""
    columns: dict[int, list[int]] = {}
    for xi, yi in cells:
        columns.setdefault(xi, []).append(yi)
    strips: list[tuple[int, int, int]] = []  # (column, first row, last row)
    for xi in sorted(columns):
        rows = sorted(columns[xi])
        first = previous = rows[0]
        for yi in rows[1:]:
            if yi != previous + 1:
                strips.append((xi, first, previous))
                first = yi
            previous = yi
        strips.append((xi, first, previous))
    boxes: list[tuple[int, int, int, int]] = []  # (first column, last column, first row, last row)
    open_runs: dict[tuple[int, int], int] = {}
    for xi, first, last in strips:
        key = (first, last)
        index = open_runs.get(key)
        if index is not None and boxes[index][1] == xi - 1:
            c0, _c1, r0, r1 = boxes[index]
            boxes[index] = (c0, xi, r0, r1)
        else:
            open_runs[key] = len(boxes)
            boxes.append((xi, xi, first, last))
    xs, ys = cuts
    return [IndexBox(xs[c0][0], xs[c1][1], ys[r0][0], ys[r1][1]) for c0, c1, r0, r1 in boxes]
