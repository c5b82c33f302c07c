"""Why the collision model needs more phases than the exact rule: the exact plan's moves and poses it refuses.

Run from the project root:

    PYTHONPATH=. python tests/expert/collision_explain.py diagonal-3 room-105 --detail 4

For each named scenario of ``collision_study.scenarios`` (or ``corridor-504``: the family
``corridor`` at seed 504), the exhaustive search of the exact rule
(``lattice_search.search``) gives one optimal plan; each of its moves is tested against
Eq. 18 as the planner writes it (``plan(..., corner_detail=d)``: some region of every
rectangle holds both ends, :func:`expert.milp.grid.move_regions`, and the start's tangents
for the first move with ``--tangents``; ``--poses``: with ``corner_poses`` and
``pose_tangents``), and each pick and place pose against the pose options' boxes
(:func:`expert.milp.options.pose_options`). It prints what is refused and by which
rectangle. Units: metres.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np
from collision_study import scenarios
from lattice_search import search
from test_lattice_search import RESOLUTION

from expert.milp.grid import DiagonalPlane, Grid, move_regions, point_in_move_region, start_tangents
from expert.milp.problem import Problem, prepare
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import get_family
from fetchcarry_env.geometry import Point, Rect
from fetchcarry_env.scenario import Scenario


def _holds(plane, index: tuple[int, int]) -> bool:
    if isinstance(plane, DiagonalPlane):
        return plane.holds_at(*index)
    return plane.holds(index[plane.axis])


def move_refused_by(grid: Grid, scenario: Scenario, a: Point, b: Point, first: bool) -> list[str]:
    """The rectangles no region of Eq. 18 of which holds both ends of ``a -> b`` (``a``: the start if ``first``)."""
    radius, out = scenario.robot.radius, []
    rects: list[tuple[str, Rect]] = [(t.id, t.rect) for t in scenario.tables]
    rects += [(o.id, o.rect) for o in scenario.obstacles]
    ib = grid.lattice.index(b)
    for name, rect in rects:
        regions = move_regions(grid, rect, radius)
        if first:
            ok = any(point_in_move_region(grid, a, rect, radius, n) and _holds(p, ib) for n, p in enumerate(regions))
            tangents = start_tangents(grid, a, rect, radius) if grid.first_move_tangents else ()
            ok = ok or any(_holds(p, ib) for p in tangents)
        else:
            ia = grid.lattice.index(a)
            ok = any(_holds(p, ia) and _holds(p, ib) for p in regions)
        if not ok:
            out.append(name)
    return out


def pose_refused(problem: Problem, kind: str, target: str, b: Point) -> bool:
    """True when no pose option of ``kind`` for ``target`` has ``b`` (a lattice point) in its box."""
    i, j = problem.grid.lattice.index(b)
    return not any(o.box.contains(i, j) for o in problem.options if o.kind == kind and o.target == target)


def explain(scenario: Scenario, detail: int, tangents: bool, poses: bool = False) -> list[str]:
    """One line per phase of the exact rule's optimal plan: base, action and what the model refuses there."""
    lattice = Lattice.over(scenario.area, RESOLUTION)
    exact = search(scenario, lattice, max_phases=8)
    problem = prepare(
        scenario, lattice, corner_detail=detail, first_move_tangents=tangents, corner_poses=poses, pose_tangents=poses
    )
    (obj,) = scenario.objects
    lines = [f"{scenario.name}: exact {exact.phases} phases, Eq. 1 {exact.objective}"]
    previous = scenario.robot.start
    for k, (base, action) in enumerate(exact.path, start=1):
        notes = [f"move refused by {n}" for n in move_refused_by(problem.grid, scenario, previous, base, k == 1)]
        if action and pose_refused(problem, action, obj.id, base):
            notes.append(f"{action} pose not offered")
        lines.append(f"  phase {k}: {base} {action or '-'}  {'; '.join(notes) or 'ok'}")
        previous = base
    return lines


def named(name: str) -> Scenario:
    """A scenario of the study by name, or ``family-seed`` of a single-object family."""
    for scenario in scenarios(10, 2):
        if scenario.name == name:
            return scenario
    family, seed = name.rsplit("-", 1)
    return dataclasses.replace(get_family(family).sample(np.random.default_rng(int(seed))), name=name)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("names", nargs="+")
    parser.add_argument("--detail", type=int, default=4, help="corner_detail of the model tested")
    parser.add_argument("--tangents", action="store_true", help="with the start's tangents (first_move_tangents)")
    parser.add_argument("--poses", action="store_true", help="with corner_poses and pose_tangents")
    args = parser.parse_args()
    for name in args.names:
        print("\n".join(explain(named(name), args.detail, args.tangents, args.poses)), flush=True)


if __name__ == "__main__":
    main()
