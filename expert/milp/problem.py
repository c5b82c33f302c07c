"""The planning problem after preprocessing: what must be delivered and pushed, and every pose option.

:func:`prepare` turns a scenario (and the action lattice) into a :class:`Problem`: the
objects still to deliver, the clutter that covers their goals and how it can be
pushed (the paper's IV-E preprocessing, :mod:`expert.milp.push`), and the *pose
options*: every way the arm can pick, place or push, each with the box of lattice
points its base may stand on (:mod:`expert.milp.postures`). None of this depends on
the number of phases, so the iterative deepening prepares once and builds one MILP
per number of phases from the same problem.

Units are metres, except lattice indices.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from expert.milp.area import area_is_empty
from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import Grid
from expert.milp.options import PoseOption, pose_options
from expert.milp.strokes import PushPlan, plan_pushes
from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import discs_overlap
from fetchcarry_env.scenario import Scenario

AT_GOAL_TOL = 1e-3  # metres: an object (not held) this close to its goal needs nothing (the validator's tolerance)


@dataclass(frozen=True)
class Problem:
    """Everything the MILP needs that does not depend on the number of phases."""

    scenario: Scenario
    grid: Grid
    holding: str | None
    deliver: tuple[str, ...]  # objects to deliver, the held one (if any) included
    delivered: tuple[str, ...]  # objects already standing at their goals
    covers: dict[str, tuple[str, ...]]  # object id -> ids of the clutter covering its goal
    pushes: PushPlan
    blocking_objects: tuple[tuple[str, str], ...]  # (a, b): b stands on a's goal, so b is picked before a is placed
    options: tuple[PoseOption, ...]
    start_index: tuple[int, int] | None  # the start's lattice point if the start lies exactly on one
    infeasible: str | None = None  # why no plan can exist, when preprocessing already knows
    earliest: tuple[int, ...] = ()  # earliest[d]: first phase by which d objects can be delivered (bounds.Skeleton)
    min_travel: float = 0.0  # metres: a lower bound on the travel term of Eq. 1 (bounds.min_travel)
    notes: dict = field(default_factory=dict)

    def options_of(self, kind: str, target: str | None = None) -> list[int]:
        """Indices of the options of ``kind`` (for ``target`` if given)."""
        return [n for n, o in enumerate(self.options) if o.kind == kind and (target is None or o.target == target)]


def prepare(
    scenario: Scenario,
    lattice: Lattice,
    holding: str | None = None,
    integral: bool = True,
    deadline: Deadline = NEVER,
) -> Problem:
    """Preprocess ``scenario`` on ``lattice``; ``holding`` is the id of an object already in the hand.

    Raises :class:`~expert.milp.deadline.TimeUp` once ``deadline`` has passed.
    """
    robot = scenario.robot
    grid = Grid.for_area(lattice, scenario.area, robot.radius, integral)
    ids = {o.id for o in scenario.objects}
    if holding is not None and holding not in ids:
        raise ValueError(f"holding {holding!r} is not an object of scenario {scenario.name!r}")
    delivered = tuple(o.id for o in scenario.objects if o.id != holding and math.dist(o.start, o.goal) <= AT_GOAL_TOL)
    deliver = tuple(o.id for o in scenario.objects if o.id not in delivered)
    covers = {
        o.id: tuple(c.id for c in scenario.clutter if c.rect.overlaps_disc(o.goal, o.radius))
        for o in scenario.objects
        if o.id in deliver
    }
    deadline.check()
    pushes = plan_pushes(scenario, grid, covers, holding)
    deadline.check()
    blocking = _blocking_objects(scenario, deliver, holding)
    start_index = lattice.index(robot.start) if lattice.on_lattice(robot.start) else None
    if start_index is not None and not grid.domain.contains(*start_index):
        start_index = None
    options = pose_options(scenario, grid, deliver, holding, pushes, deadline)
    problem = Problem(
        scenario=scenario,
        grid=grid,
        holding=holding,
        deliver=deliver,
        delivered=delivered,
        covers=covers,
        pushes=pushes,
        blocking_objects=blocking,
        options=tuple(options),
        start_index=start_index,
    )
    reason = _structural_infeasibility(problem)
    if reason is not None:
        problem = dataclasses.replace(problem, infeasible=reason)
    return problem


def _blocking_objects(scenario: Scenario, deliver: tuple[str, ...], holding: str | None) -> tuple[tuple[str, str], ...]:
    """Pairs ``(a, b)``: object ``b`` stands (at its start) where ``a`` is to be placed."""
    out = []
    for a in scenario.objects:
        if a.id not in deliver:
            continue
        for b in scenario.objects:
            if b.id != a.id and b.id != holding and discs_overlap(a.goal, a.radius, b.start, b.radius):
                out.append((a.id, b.id))
    return tuple(out)


def _structural_infeasibility(problem: Problem) -> str | None:
    """A reason no number of phases can help, or None (cheap checks only; the MILP decides the rest)."""
    scenario = problem.scenario
    if area_is_empty(problem.grid):
        return "no lattice point keeps the base disc inside the area (Eq. 27)"
    objects = {o.id: o for o in scenario.objects}
    for a in problem.deliver:
        for b in problem.deliver:
            if a < b and discs_overlap(objects[a].goal, objects[a].radius, objects[b].goal, objects[b].radius):
                return f"the goals of {a!r} and {b!r} overlap"
    for a, b in problem.blocking_objects:
        if b not in problem.deliver:
            return f"object {b!r} stands on the goal of {a!r} and is already delivered"
    for object_id in problem.deliver:
        if object_id != problem.holding and not problem.options_of("pick", object_id):
            return f"no base pose reaches object {object_id!r} at its start with a clear arm line"
        if not problem.options_of("place", object_id):
            return f"no base pose reaches the goal of {object_id!r} with a clear arm line"
    for clutter_id in problem.pushes.pushable:
        if not problem.options_of("push", clutter_id):
            return f"clutter {clutter_id!r} covers a goal and cannot be pushed off it in any allowed direction"
    return None
