"""Collision avoidance (the paper's Eq. 18) and the arm line (Eq. 19).

Eq. 18: every table and obstacle ``j`` is grown by the robot's radius and defines
overlapping regions ``R_{j,n}`` (Fig. 2: the half-planes right of, left of, above and
below it). Both ends of every move lie in one common region of every such rectangle:

    OR_n (p_{k-1} in R_{j,n}) AND (p_k in R_{j,n}),

linearised with one binary ``r_{k,j,n}`` per move, rectangle and region,
``sum_n r_{k,j,n} = 1`` and, per region, a big-M bound on both ends
(``M`` = the distance from the bound to the far end of the base's domain, the tightest
valid value). The segment then stays in a half-plane that the disc's centre must not
leave, so the whole swept disc is clear.

The paper's four regions are the sides of the grown rectangle, whose square corners
are not part of the disc-swept shape (the exact rule: the base disc swept along the
move stays off the rectangle). We add four more regions that cut those corners at 45
degrees (:func:`expert.milp.grid.move_regions`): the free side of each of the eight
edges of an octagon that holds the rounded rectangle and touches it. Diagonal moves
past a corner and diagonal gaps between two rectangles are then usable
(``docs/formulation.md``, "Collision model", measures what is left to the exact rule).
Pruned exactly:

- regions that no lattice point of the domain (Eq. 27) lies in are dropped;
- a rectangle with a region that holds the whole domain needs no constraint;
- with one region left, the bounds are hard (no binary);
- phase 0 is a constant (the exact start): only the regions that hold it count;
- where an action that must happen can only happen at one phase (the action windows),
  the base there lies in one of its options' boxes: regions that miss all of them are
  dropped for the moves ending or starting there.

Eq. 19 (the arm does not reach across an obstacle or clutter: the base and the hand
in one common region of the rectangle) is applied to the pose options before the
solve (:mod:`expert.milp.postures`), because the hand's point is known per option.
Pushable clutter moves, so an option that it would block in some position gets, for
every phase, ``sum_{o blocked by (c, p)} z_{o,k} <= 1 - [c stands at p during phase k]``
(:func:`add_arm_constraints`), the position indicator being linear in the push binaries.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pyscipopt import quicksum

from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import DiagonalPlane, Plane, move_regions, point_in_move_region

if TYPE_CHECKING:
    from expert.milp.variables import Milp


class Infeasible(Exception):
    """Raised while building when the model is infeasible for a reason known without solving."""


def add_collision_constraints(milp: Milp, deadline: Deadline = NEVER) -> None:
    """Eq. 18 for every move and every table and obstacle, with the octagon's eight regions."""
    problem, model, grid = milp.problem, milp.model, milp.problem.grid
    scenario = problem.scenario
    radius = scenario.robot.radius
    start = scenario.robot.start
    domain = grid.domain
    rects = [(t.id, t.rect) for t in scenario.tables] + [(o.id, o.rect) for o in scenario.obstacles]
    for name, rect in rects:
        deadline.check()
        planes = move_regions(grid, rect, radius)
        usable = [n for n, plane in enumerate(planes) if domain.meets(plane)]
        if any(domain.inside(planes[n]) for n in usable):
            continue
        at_start = [n for n in usable if point_in_move_region(grid, start, rect, radius, n)]
        for k in range(1, milp.n_phases):
            ends = (k - 1, k) if k > 1 else (k,)
            regions = [n for n in (at_start if k == 1 else usable) if _possible(milp, planes[n], ends)]
            if not regions:
                raise Infeasible(f"no region of {name!r} holds both ends of move {k}")
            if len(regions) == 1:
                milp.regions.append((k, [planes[regions[0]]], None))
                for e in ends:
                    model.addCons(_in_plane(milp, planes[regions[0]], e, None), name=f"eq18_{name}_{k}_{e}")
                continue
            chosen = [model.addVar(f"r_{name}_{k}_{n}", vtype="B") for n in regions]
            model.addCons(quicksum(chosen) == 1, name=f"eq18_{name}_{k}")
            milp.regions.append((k, [planes[n] for n in regions], chosen))
            for n, r in zip(regions, chosen, strict=True):
                plane = planes[n]
                for e in ends:
                    model.addCons(_in_plane(milp, plane, e, r), name=f"eq18_{name}_{k}_{n}_{e}")
                    for group, terms in _poses_outside(milp, e, plane).items():
                        model.addCons(r + quicksum(terms) <= 1, name=f"eq18_link_{name}_{k}_{n}_{e}_{group}")


def _possible(milp: Milp, plane: Plane, ends: tuple[int, ...]) -> bool:
    """False when some end of the move is confined to boxes that all miss ``plane`` (an action forced there)."""
    for e in ends:
        boxes = milp.base_boxes(e)
        if boxes is not None and all(milp.misses(box, plane) for box in boxes):
            return False
    return True


def _in_plane(milp: Milp, plane: Plane, e: int, chosen):
    """The row "base_e lies in ``plane``", relaxed by big-M when ``chosen`` (a binary) is 0; None: hard."""
    grid = milp.problem.grid
    rhs = grid.rhs(plane)
    if isinstance(plane, DiagonalPlane):
        value = plane.su * milp.u[e] + plane.sv * milp.v[e]
        lowest = grid.plane_value_range(plane)[0]
        return value >= rhs if chosen is None else value >= rhs - (rhs - lowest) * (1 - chosen)
    coord = (milp.u, milp.v)[plane.axis][e]
    lo, hi = grid.var_bounds(plane.axis)
    if plane.upper:
        return coord <= rhs if chosen is None else coord <= rhs + (hi - rhs) * (1 - chosen)
    return coord >= rhs if chosen is None else coord >= rhs - (rhs - lo) * (1 - chosen)


def _poses_outside(milp: Milp, e: int, plane) -> dict[str, list]:
    """Per group of mutually exclusive options, those that put base_e outside ``plane`` (valid cuts on Eq. 18).

    Groups: picks and places at phase e; pushes at e + 1 (they start at base_e); pushes
    at e (they end at base_e). At most one option of a group is chosen.
    """
    options = milp.problem.options
    out: dict[str, list] = {}
    if e >= 1:
        out["act"] = [z for o, z in milp.arm_options_at(e) if milp.misses(options[o].box, plane)]
        out["push_end"] = [z for o, z in milp.push_options_at(e) if milp.misses(options[o].end_box, plane)]
    if e + 1 < milp.n_phases:
        out["push_start"] = [z for o, z in milp.push_options_at(e + 1) if milp.misses(options[o].box, plane)]
    return {group: terms for group, terms in out.items() if terms}


def add_arm_constraints(milp: Milp) -> None:
    """Eq. 19 against pushable clutter, whose position depends on the pushes done so far."""
    problem, model = milp.problem, milp.model
    for k in range(1, milp.n_phases):
        groups: dict[tuple[str, str], list] = {}
        for o, z in milp.z[k].items():
            for state in sorted(problem.options[o].forbidden):  # a fixed order: not the set's, which hashing decides
                groups.setdefault(state, []).append(z)
        for (clutter_id, position), terms in groups.items():
            if position == "start":
                allowed = milp.pushed[clutter_id][k - 1]
            else:
                allowed = 1 - milp.pushed_towards(clutter_id, position)[k - 1]
            model.addCons(quicksum(terms) <= allowed, name=f"eq19_{clutter_id}_{position}_{k}")
