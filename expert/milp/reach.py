"""Which lattice points the base can get to at all: a cheap proof that no number of phases helps.

The free lattice points are those in one region of every table and obstacle (the
eight regions outside its octagon, :func:`expert.milp.grid.move_regions`: Eq. 18's
per-point condition) inside the domain (Eq. 27). A straight move between two points
that share a region of every rectangle stays in the intersection of those regions, an
octilinear convex set (edges along the axes and the diagonals, at whole lattice
values); the lattice points of such a set are 8-connected (per column they form an
interval whose ends move by at most one cell from column to column). Hence the points
reachable by any sequence of moves lie in the 8-connected components of the points
one move from the start. Options outside them can
never be used; if an action loses all its options, the problem is infeasible for every
number of phases. The planner runs this before any MILP (a few milliseconds: array
operations over the lattice), so an object or goal that no pose reaches is reported at
once whatever the number of objects.

The reason names the action and the narrowest gap on the widest way there
(:func:`narrowest_gap`): over every 8-connected lattice path from the start's
component to a pose of the action, the one whose least clearance (distance of the
base's centre to the nearest table, obstacle or edge of the area) is largest; its
tightest point lies between two items, and their distance is the gap the base would
have to pass. A gap is passable straight through when a lattice line lies at least the
radius from both of its sides: always from ``2 r + resolution`` on (0.49 m for the
0.44 m base on the 5 cm lattice), never below ``2 r``, and in between depending on where
the lattice lines fall.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import DiagonalPlane, IndexBox, move_regions, point_in_move_region
from expert.milp.problem import Problem
from fetchcarry_env.geometry import Rect

EIGHT_NEIGHBOURS = np.ones((3, 3), dtype=bool)


def reachable_mask(problem: Problem, deadline: Deadline = NEVER) -> np.ndarray:
    """Boolean array over the domain's lattice points (``[i - i_lo, j - j_lo]``): reachable from the start."""
    return _reachable(*free_and_seed(problem, deadline))


def _reachable(free: np.ndarray, seed: np.ndarray) -> np.ndarray:
    """The components of ``free`` that hold a point of ``seed``, and ``seed`` itself (one move from the start)."""
    labels, _ = ndimage.label(free, structure=EIGHT_NEIGHBOURS)
    hit = np.unique(labels[seed & free])
    return np.isin(labels, hit[hit > 0]) | seed


def free_and_seed(problem: Problem, deadline: Deadline = NEVER) -> tuple[np.ndarray, np.ndarray]:
    """The free lattice points of the domain (Eq. 18 per point) and those one straight move from the start.

    A point outside the window ``lo < i < hi`` (and ``j``) of a rectangle's four sides is in a
    side region, so each rectangle's test runs on its window only (a thousand obstacles in
    tens of milliseconds); the start's regions restrict the seed over the whole domain.
    """
    scenario = problem.scenario
    grid, domain = problem.grid, problem.grid.domain
    radius, start = scenario.robot.radius, scenario.robot.start
    ii = np.arange(domain.i_lo, domain.i_hi + 1)[:, None]
    jj = np.arange(domain.j_lo, domain.j_hi + 1)[None, :]
    free = np.ones((ii.shape[0], jj.shape[1]), dtype=bool)
    seed = np.ones_like(free)
    for rect in (*(t.rect for t in scenario.tables), *(o.rect for o in scenario.obstacles)):
        deadline.check()
        planes = move_regions(grid, rect, radius)
        east, west, north, south = planes[:4]  # i >= east.bound, i <= west.bound, j >= north.bound, j <= south.bound
        i0, i1 = max(west.bound + 1, domain.i_lo), min(east.bound - 1, domain.i_hi)
        j0, j1 = max(south.bound + 1, domain.j_lo), min(north.bound - 1, domain.j_hi)
        if i0 <= i1 and j0 <= j1:
            wi, wj = ii[i0 - domain.i_lo : i1 - domain.i_lo + 1], jj[:, j0 - domain.j_lo : j1 - domain.j_lo + 1]
            cut = np.zeros((wi.shape[0], wj.shape[1]), dtype=bool)
            for plane in planes[4:]:
                cut |= _member(plane, wi, wj)
            free[i0 - domain.i_lo : i1 - domain.i_lo + 1, j0 - domain.j_lo : j1 - domain.j_lo + 1] &= cut
        with_start = [plane for n, plane in enumerate(planes) if point_in_move_region(grid, start, rect, radius, n)]
        near = np.zeros_like(free)
        for plane in with_start:  # exactly: the seed needs no connectivity argument
            near |= _member(plane, ii, jj, relaxed=False)
        seed &= near
    return free, seed


def _member(plane, ii: np.ndarray, jj: np.ndarray, relaxed: bool = True) -> np.ndarray:
    """The lattice points ``ii x jj`` (index columns and rows) in ``plane``; ``relaxed``: a cut other than 45 degrees
    is widened by half a cell (module doc)."""
    if isinstance(plane, DiagonalPlane):
        slack = 0 if plane.octilinear or not relaxed else (abs(plane.su) + abs(plane.sv)) // 2
        return plane.su * ii + plane.sv * jj >= plane.bound - slack
    index = ii if plane.axis == 0 else jj
    member = index <= plane.bound if plane.upper else index >= plane.bound
    return np.broadcast_to(member, (ii.shape[0], jj.shape[1]))


def unreachable_reason(problem: Problem, deadline: Deadline = NEVER) -> str | None:
    """Why some action can never be done (all its poses unreachable), with the narrowest gap on the way; or None."""
    free, seed = free_and_seed(problem, deadline)
    mask = _reachable(free, seed)
    domain = problem.grid.domain
    usable: dict[tuple[str, str], bool] = {}
    boxes: dict[tuple[str, str], list[IndexBox]] = {}
    for option in problem.options:
        ok = _any_in(mask, domain, option.box)
        if option.push is not None:
            ok = ok and _any_in(mask, domain, option.box.shifted(*option.push.cells))
        key = (option.kind, option.target)
        usable[key] = usable.get(key, False) or ok
        boxes.setdefault(key, []).append(option.box)
    wanted = [("pick", i) for i in problem.deliver if i != problem.holding]
    wanted += [("place", i) for i in problem.deliver] + [("push", c) for c in problem.pushes.pushable]
    for key in wanted:
        if not usable.get(key, False):
            verb = {"pick": "picks", "place": "places", "push": "pushes"}[key[0]]
            reason = f"the base cannot get to any pose that {verb} {key[1]!r}"
            gap = narrowest_gap(problem, boxes.get(key, []), deadline, seed)
            return reason if gap is None else f"{reason}: {gap.sentence(problem)}"
    return None


def _any_in(mask: np.ndarray, domain: IndexBox, box: IndexBox) -> bool:
    """Whether ``mask`` (over ``domain``) holds a point of ``box``."""
    box = box.intersect(domain)
    if box.empty:
        return False
    return bool(
        mask[
            box.i_lo - domain.i_lo : box.i_hi - domain.i_lo + 1, box.j_lo - domain.j_lo : box.j_hi - domain.j_lo + 1
        ].any()
    )


@dataclass(frozen=True)
class Gap:
    """The tightest point of the widest way to some poses: where it is and the two items that pinch it (metres)."""

    point: tuple[float, float]
    clearance: float  # of the base's centre at that point: the radius it would need to be at most
    sides: tuple[str, str]  # the items on either side (a table's or obstacle's id, or "the area's edge")
    width: float  # the distance between them: the gap the base has to pass

    def sentence(self, problem: Problem) -> str:
        """The gap in words, with the rule that a gap must meet on the lattice."""
        robot, resolution = problem.scenario.robot, problem.grid.resolution
        if self.width <= 0.0:
            return f"the way is closed where {self.sides[0]!r} meets {self.sides[1]!r} near {_at(self.point)}"
        return (
            f"the narrowest gap on the widest way there is {self.width:.3f} m, between {self.sides[0]!r} and "
            f"{self.sides[1]!r} near {_at(self.point)}; the {2 * robot.radius:.2f} m base passes straight through a "
            f"gap between parallel sides only where a lattice line lies {robot.radius:.3f} m or more from both "
            f"(every such gap of {2 * robot.radius + resolution:.3f} m or more, on this {resolution:g} m lattice)"
        )


def narrowest_gap(
    problem: Problem, targets: list[IndexBox], deadline: Deadline = NEVER, seed: np.ndarray | None = None
) -> Gap | None:
    """The tightest point of the widest 8-connected lattice way from the start's points to ``targets``.

    Clearance is the exact distance of a lattice point to the nearest table or obstacle
    (or to the area's edge, minus nothing: the disc must stay inside). The widest way's
    least clearance ``c*`` is found by bisection over the clearance values (one labelling
    each); its tightest point is a point of clearance ``c*`` next to the start's side at
    the next level up. None when no target point lies in the domain.
    """
    grid, domain = problem.grid, problem.grid.domain
    clearance, nearest, second, second_item, items = _clearance(problem, deadline)
    if seed is None:
        _, seed = free_and_seed(problem, deadline)
    target = np.zeros_like(seed)
    for box in targets:
        box = box.intersect(domain)
        if not box.empty:
            target[
                box.i_lo - domain.i_lo : box.i_hi - domain.i_lo + 1, box.j_lo - domain.j_lo : box.j_hi - domain.j_lo + 1
            ] = True
    if not target.any() or not seed.any():
        return None
    levels = np.unique(clearance)
    lo, hi = 0, len(levels) - 1  # levels[lo] connects (everything does); find the highest level that does
    if not _connects(clearance >= levels[lo], seed, target):
        return None
    while lo < hi:
        deadline.check()
        mid = (lo + hi + 1) // 2
        if _connects(clearance >= levels[mid], seed, target):
            lo = mid
        else:
            hi = mid - 1
    c_star = levels[lo]
    above = clearance > c_star
    labels, _ = ndimage.label(above, structure=EIGHT_NEIGHBOURS)
    start_labels = np.unique(labels[seed & above])
    start_side = np.isin(labels, start_labels[start_labels > 0]) | seed
    exits = (clearance == c_star) & ndimage.binary_dilation(start_side, structure=EIGHT_NEIGHBOURS)
    if not exits.any():
        exits = clearance == c_star
    pinch = np.where(exits, second, np.inf)  # the most pinched exit: both of its sides closest
    a, b = np.unravel_index(int(np.argmin(pinch)), pinch.shape)
    point = grid.point(int(a) + domain.i_lo, int(b) + domain.j_lo)
    first, other = items[int(nearest[a, b])], items[int(second_item[a, b])]
    area = problem.scenario.area
    width = _item_distance(first, other, point, area) if first is not other else 2 * float(c_star)
    return Gap(point, float(c_star), (first[0], other[0]), width)


def _connects(level: np.ndarray, seed: np.ndarray, target: np.ndarray) -> bool:
    """Whether some point of ``seed`` and some of ``target`` share an 8-connected component of ``level``."""
    labels, _ = ndimage.label(level, structure=EIGHT_NEIGHBOURS)
    from_seed = np.unique(labels[seed & level])
    from_seed = from_seed[from_seed > 0]
    return bool(from_seed.size) and bool(np.isin(labels[target & level], from_seed).any())


AREA_EDGE = "the area's edge"


def _clearance(problem: Problem, deadline: Deadline) -> tuple[np.ndarray, ...]:
    """Per domain point: the distances to the nearest and second-nearest items (metres) and which they are.

    Items are the area's edge (index 0) and every table and obstacle; also returns them as
    ``(name, rect)``. Distances are capped at ``2 r`` plus two cells (no gap wider matters),
    so each rectangle is measured on its own window of the lattice.
    """
    scenario, grid, domain = problem.scenario, problem.grid, problem.grid.domain
    cap = 2 * scenario.robot.radius + 2 * grid.resolution
    x = grid.point(domain.i_lo, 0)[0] + grid.resolution * np.arange(domain.i_hi - domain.i_lo + 1)[:, None]
    y = grid.point(0, domain.j_lo)[1] + grid.resolution * np.arange(domain.j_hi - domain.j_lo + 1)[None, :]
    area = scenario.area
    items: list[tuple[str, Rect | None]] = [(AREA_EDGE, None)]
    edge = np.minimum(np.minimum(x - area.min_x, area.max_x - x), np.minimum(y - area.min_y, area.max_y - y))
    best = np.minimum(edge, cap)
    nearest = np.zeros(best.shape, dtype=np.int32)
    second = np.full(best.shape, cap)
    second_item = np.zeros(best.shape, dtype=np.int32)
    for thing in (*scenario.tables, *scenario.obstacles):
        deadline.check()
        items.append((thing.id, thing.rect))
        n, rect = len(items) - 1, thing.rect
        i0, i1 = np.searchsorted(x[:, 0], [rect.min_x - cap, rect.max_x + cap])
        j0, j1 = np.searchsorted(y[0], [rect.min_y - cap, rect.max_y + cap])
        if i0 >= i1 or j0 >= j1:
            continue
        window = (slice(i0, i1), slice(j0, j1))
        distance = _rect_distance(x[i0:i1], y[:, j0:j1], rect)
        b, near, sec, sec_item = best[window], nearest[window], second[window], second_item[window]
        closer = distance < b
        runner_up = ~closer & (distance < sec)
        second[window] = np.where(closer, b, np.where(runner_up, distance, sec))
        second_item[window] = np.where(closer, near, np.where(runner_up, n, sec_item))
        best[window] = np.where(closer, distance, b)
        nearest[window] = np.where(closer, n, near)
    return best, nearest, second, second_item, items


def _rect_distance(x: np.ndarray, y: np.ndarray, rect: Rect) -> np.ndarray:
    dx = np.maximum(np.maximum(rect.min_x - x, 0.0), x - rect.max_x)
    dy = np.maximum(np.maximum(rect.min_y - y, 0.0), y - rect.max_y)
    return np.hypot(dx, dy)


def _item_distance(
    a: tuple[str, Rect | None], b: tuple[str, Rect | None], point: tuple[float, float], area: Rect
) -> float:
    """The distance between two items (metres): two rectangles, or a rectangle and the area's side nearest ``point``."""
    if a[1] is not None and b[1] is not None:
        ra, rb = a[1], b[1]
        dx = max(ra.min_x - rb.max_x, rb.min_x - ra.max_x, 0.0)
        dy = max(ra.min_y - rb.max_y, rb.min_y - ra.max_y, 0.0)
        return math.hypot(dx, dy)
    rect = a[1] if a[1] is not None else b[1]
    sides = (
        (point[0] - area.min_x, rect.min_x - area.min_x),
        (area.max_x - point[0], area.max_x - rect.max_x),
        (point[1] - area.min_y, rect.min_y - area.min_y),
        (area.max_y - point[1], area.max_y - rect.max_y),
    )
    return max(0.0, min(sides)[1])


def _at(point: tuple[float, float]) -> str:
    return f"({point[0]:.2f}, {point[1]:.2f})"
