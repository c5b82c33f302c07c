"""A fast first plan: deliver the objects one at a time, each by the single-object MILP.

The decoupled plan solves, object after object, the planner's own MILP for that one
object from where the previous delivery left the robot (the other objects standing
where they are, as if delivered; pushed clutter where it was pushed). Single-object
models solve in tens of milliseconds, so the whole plan comes quickly. It is a valid
plan of the full problem (every sub-plan obeys the same rules, and the state carries
over exactly), usually with as many phases as the optimum or a few more, and a
higher Eq. 1. :func:`expert.planner.plan` makes one first, nearest object first
with SCIP stopped at its first solution of each sub-plan (before any bound of the whole
problem, so that a short time limit has a valid plan), and uses it as the answer of last resort
(status ``feasible``) and, when it has no more phases than the model being solved,
as SCIP's first incumbent (:mod:`expert.milp.warm`).

Units are metres and seconds.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence

from expert.milp.deadline import Deadline, TimeUp
from expert.milp.decode import SolvedPhase
from expert.milp.problem import Problem
from expert.plans import Phase, Plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import Scenario

Planner = Callable[..., Plan]


def decoupled_plan(
    scenario: Scenario,
    order: Sequence[str],
    lattice: Lattice,
    deadline: Deadline,
    planner: Planner,
    lookahead: int = 1,
    nearest: bool = False,
) -> tuple[Phase, ...] | None:
    """Phases of a plan delivering the objects one at a time, trying them in ``order``; None if it fails.

    ``nearest``: ignore ``order``'s sequence and take, at each step, the object whose
    start is closest to the base (Euclidean distance): an order that needs no search.

    Each step solves the MILP for the next ``lookahead`` objects of ``order`` (the others
    standing where they are) and keeps its phases up to its first place: with
    ``lookahead = 2`` the place of one object is chosen knowing the next one (fewer
    phases at the junctions, at the price of two-object models).
    ``planner`` is :func:`expert.planner.plan` (passed in to avoid an import circle).
    Raises :class:`~expert.milp.deadline.TimeUp` when ``deadline`` passes.
    """
    phases: list[Phase] = []
    base, heading = scenario.robot.start, scenario.robot.heading
    objects = {o.id: o.start for o in scenario.objects}
    clutter = {c.id: c.rect.center for c in scenario.clutter}
    todo = list(order)
    while todo:
        if nearest:
            todo.sort(key=lambda i: math.dist(objects[i], base))
        for first in range(len(todo)):
            left = deadline.left()
            if left <= 0:
                raise TimeUp
            targets = (todo[first:] + todo[:first])[:lookahead]
            sub = _sub_problem(scenario, targets, base, heading, objects, clutter)
            result = planner(sub, time_limit=left, lattice=lattice)
            if result.found:
                break
        else:
            return None
        kept = _through_first_place(result.phases)
        todo.remove(kept[-1].target)
        if not phases:
            phases.append(kept[0])
        phases.extend(kept[1:])
        last = kept[-1]
        base, heading = last.base, last.heading
        objects, clutter = dict(last.objects), dict(last.clutter)
    return tuple(phases)


def _through_first_place(phases: Sequence[Phase]) -> list[Phase]:
    end = next(k for k, p in enumerate(phases) if p.action == "place")
    return list(phases[: end + 1])


def _sub_problem(
    scenario: Scenario,
    targets: Sequence[str],
    base,
    heading,
    objects: dict,
    clutter: dict,
) -> Scenario:
    """The sub-problem: only ``targets`` to deliver; every other object stays where it stands."""
    moved_objects = tuple(
        dataclasses.replace(o, start=objects[o.id], goal=o.goal if o.id in targets else objects[o.id])
        for o in scenario.objects
    )
    moved_clutter = tuple(dataclasses.replace(c, rect=_moved(c.rect, clutter[c.id])) for c in scenario.clutter)
    return dataclasses.replace(
        scenario,
        robot=dataclasses.replace(scenario.robot, start=base, heading=heading),
        objects=moved_objects,
        clutter=moved_clutter,
    )


def _moved(rect: Rect, center) -> Rect:
    cx, cy = rect.center
    return rect.translate(center[0] - cx, center[1] - cy)


def steps_of(problem: Problem, phases: Sequence[Phase]) -> list[SolvedPhase] | None:
    """The plan's phases after the start as MILP steps (lattice cell, pose option); None if one does not map."""
    lattice = problem.grid.lattice
    steps: list[SolvedPhase] = []
    previous = problem.start_index
    for phase in phases[1:]:
        if not lattice.on_lattice(phase.base):
            return None
        cell = lattice.index(phase.base)
        option = None
        if phase.action != "move":
            acting = previous if phase.action == "push" else cell
            if acting is None:
                return None
            option = next(
                (
                    o
                    for o in problem.options
                    if o.kind == phase.action
                    and o.target == phase.target
                    and o.heading == phase.heading
                    and o.posture == phase.posture
                    and o.box.contains(*acting)
                    and (o.push is None or (acting[0] + o.push.cells[0], acting[1] + o.push.cells[1]) == cell)
                ),
                None,
            )
            if option is None:
                return None
        steps.append(SolvedPhase(cell, option))
        previous = cell
    return steps
