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

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from fetchcarry_env import regions
from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import Point, Rect
from fetchcarry_env.regions import (
    DiagonalPlane,
    HalfPlane,
    IndexBox,
    Plane,
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

    @classmethod
    def for_area(cls, lattice: Lattice, area: Rect, radius: float, integral: bool = True) -> Grid:
        """The grid whose domain is every lattice point at which the base disc lies inside ``area`` (Eq. 27)."""
        return cls(lattice, regions.area_domain(lattice, area, radius), integral)

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


def move_regions(grid: Grid, rect: Rect, radius: float) -> tuple[Plane, ...]:
    """The regions of Eq. 18 in our tighter model: outside the octagon around ``rect`` grown by ``radius``.

    The first four are :func:`base_regions` (the sides of the grown rectangle); the other
    four cut its corners at 45 degrees, ``a x + b y >= a cx + b cy + radius sqrt(2)`` at corner
    ``(cx, cy)`` with ``a, b = +-1``, the tangent to the corner's quarter circle. The octagon
    holds the rectangle's disc-swept shape (every point outside it is ``radius`` or more from
    ``rect``) and touches it on every side. These are exactly the env's regions
    (:func:`fetchcarry_env.regions.octagon_regions`): a move the env accepts is one the model does.
    """
    return regions.octagon_regions(grid.lattice, rect, radius)


def point_in_move_region(grid: Grid, point: Point, rect: Rect, radius: float, region: int) -> bool:
    """Exact test of an off-lattice point against region ``region`` of :func:`move_regions`."""
    return regions.point_in_octagon_region(point, rect, radius, region)


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
