"""Which lattice points the base can get to at all: a cheap proof that no number of phases helps.

The free lattice points are those in one region of every table and obstacle (the
eight regions outside its octagon, :func:`expert.milp.grid.move_regions`: Eq. 18's
per-point condition) inside the domain (Eq. 27). A straight move between two points
that share a region of every rectangle stays in the intersection of those regions, an
octilinear convex set (edges along the axes and the diagonals, at whole lattice
values); the lattice points of such a set are 8-connected (per column they form an
interval whose ends move by at most one cell from column to column). Hence the points
reachable by any sequence of moves lie in the 8-connected components of the points
one move from the start. Options outside them can never be used; if an action loses all its options,
the problem is infeasible for every number of phases. The planner runs this only when
the first MILP it solves is infeasible, so the common case does not pay for it.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import DiagonalPlane, move_regions, point_in_move_region
from expert.milp.problem import Problem

EIGHT_NEIGHBOURS = np.ones((3, 3), dtype=bool)


def reachable_mask(problem: Problem, deadline: Deadline = NEVER) -> np.ndarray:
    """Boolean array over the domain's lattice points (``[i - i_lo, j - j_lo]``): reachable from the start."""
    scenario = problem.scenario
    grid, domain = problem.grid, problem.grid.domain
    radius = scenario.robot.radius
    ii = np.arange(domain.i_lo, domain.i_hi + 1)[:, None]
    jj = np.arange(domain.j_lo, domain.j_hi + 1)[None, :]
    free = np.ones((ii.shape[0], jj.shape[1]), dtype=bool)
    seed = np.ones_like(free)
    for rect in (*(t.rect for t in scenario.tables), *(o.rect for o in scenario.obstacles)):
        deadline.check()
        inside_any = np.zeros_like(free)
        with_start = np.zeros_like(free)
        for n, plane in enumerate(move_regions(grid, rect, radius)):
            if isinstance(plane, DiagonalPlane):
                member = plane.su * ii + plane.sv * jj >= plane.bound
            else:
                index = ii if plane.axis == 0 else jj
                member = np.broadcast_to(index <= plane.bound if plane.upper else index >= plane.bound, free.shape)
            inside_any |= member
            if point_in_move_region(scenario.robot.start, rect, radius, n):
                with_start |= member
        free &= inside_any
        seed &= with_start
    labels, _ = ndimage.label(free, structure=EIGHT_NEIGHBOURS)
    hit = np.unique(labels[seed & free])
    return np.isin(labels, hit[hit > 0])


def unreachable_reason(problem: Problem, deadline: Deadline = NEVER) -> str | None:
    """Why some action can never be done (all its poses unreachable), or None."""
    mask = reachable_mask(problem, deadline)
    domain = problem.grid.domain

    def any_reached(box) -> bool:
        box = box.intersect(domain)
        if box.empty:
            return False
        return bool(
            mask[
                box.i_lo - domain.i_lo : box.i_hi - domain.i_lo + 1, box.j_lo - domain.j_lo : box.j_hi - domain.j_lo + 1
            ].any()
        )

    usable: dict[tuple[str, str], bool] = {}
    for option in problem.options:
        ok = any_reached(option.box)
        if option.push is not None:
            ok = ok and any_reached(option.box.shifted(*option.push.cells))
        key = (option.kind, option.target)
        usable[key] = usable.get(key, False) or ok
    for object_id in problem.deliver:
        if object_id != problem.holding and not usable.get(("pick", object_id), False):
            return f"the base cannot get to any pose that picks {object_id!r}"
        if not usable.get(("place", object_id), False):
            return f"the base cannot get to any pose that places {object_id!r}"
    for clutter_id in problem.pushes.pushable:
        if not usable.get(("push", clutter_id), False):
            return f"the base cannot get to any pose that pushes {clutter_id!r}"
    return None
