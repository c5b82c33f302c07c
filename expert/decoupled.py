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
import time
from collections.abc import Callable, Sequence

from expert.approach import FreeLattice, approach, carry, moves_along, pick_leg, shortcut
from expert.milp.deadline import Deadline, TimeUp
from expert.milp.decode import SolvedPhase
from expert.milp.problem import Problem
from expert.plans import Phase, Plan, plan_objective
from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import Scenario

Planner = Callable[..., Plan]
SHORTER_SUB_PLAN_S = 1.0  # seconds the fallback gives the optimal sub-plan after a first solution of more than one step
WHOLE_LEGS_S = 5.0  # seconds, at most, for the fallback's second try (the MILP for each whole delivery)
PLACE_KEEP = 1.0  # metres of path before the goal where the fallback's moves stop and the MILP takes over


def decoupled_plan(
    scenario: Scenario,
    order: Sequence[str],
    lattice: Lattice,
    deadline: Deadline,
    planner: Planner,
    lookahead: int = 1,
    nearest: bool = False,
    holding: str | None = None,
) -> tuple[Phase, ...] | None:
    """Phases of a plan delivering the objects one at a time, trying them in ``order``; None if it fails.

    ``nearest``: ignore ``order``'s sequence and take, at each step, the object whose
    start is closest to the base (Euclidean distance): an order that needs no search.

    Each step solves the MILP for the next ``lookahead`` objects of ``order`` (the others
    standing where they are) and keeps its phases up to its first place: with
    ``lookahead = 2`` the place of one object is chosen knowing the next one (fewer
    phases at the junctions, at the price of two-object models).
    ``planner`` is :func:`expert.planner.plan` (passed in to avoid an import circle).
    ``holding``: an object already in the hand at the start; it is delivered first.
    Raises :class:`~expert.milp.deadline.TimeUp` when ``deadline`` passes.
    """
    phases: list[Phase] = []
    base, heading = scenario.robot.start, scenario.robot.heading
    objects = {o.id: o.start for o in scenario.objects}
    clutter = {c.id: c.rect.center for c in scenario.clutter}
    todo = list(order)
    if holding is not None:  # the held object first, whatever the order
        todo = [holding] + [i for i in todo if i != holding]
    while todo:
        if nearest and holding is None:
            todo.sort(key=lambda i: math.dist(objects[i], base))
        for first in range(1 if holding is not None else len(todo)):
            left = deadline.left()
            if left <= 0:
                raise TimeUp
            targets = (todo[first:] + todo[:first])[: 1 if holding is not None else lookahead]
            sub = _sub_problem(scenario, targets, base, heading, objects, clutter)
            result = planner(sub, time_limit=left, lattice=lattice, holding=holding)
            if result.found:
                break
        else:
            return None
        kept = _through_first_place(result.phases)
        if kept is None:  # the planner sees these targets delivered already: nothing to do for them
            todo = [i for i in todo if i not in targets]
            holding = None
            continue
        todo.remove(kept[-1].target)
        if not phases:
            phases.append(kept[0])
        phases.extend(kept[1:])
        last = kept[-1]
        holding = None
        base, heading = last.base, last.heading
        objects, clutter = dict(last.objects), dict(last.clutter)
    return tuple(phases)


def decoupled_apart(
    scenario: Scenario,
    order: Sequence[str],
    lattice: Lattice,
    deadline: Deadline,
    planner: Planner,
    holding: str | None = None,
) -> tuple[Phase, ...] | None:
    """The decoupled plan, nearest object first, with the long legs made by :mod:`expert.approach`; None if it fails.

    Per object: moves along the searched path and a pick the env's rules accept
    (:func:`expert.approach.pick_leg`; when none is found, moves towards the object and
    the single-object MILP for the whole delivery from there, as :func:`decoupled_plan`),
    then moves towards the goal stopping ``PLACE_KEEP`` metres of path before it, and the
    single-object MILP with the object in the hand for what is left (pushes, the place; from the pick when that fails).
    ``planner`` takes ``first=False`` for an optimal sub-plan (it stops at SCIP's first
    solution otherwise): tried for ``SHORTER_SUB_PLAN_S`` after a first solution of more
    than one step, and kept when it has no more phases.
    Raises :class:`~expert.milp.deadline.TimeUp` when ``deadline`` passes.
    """
    space = FreeLattice(scenario, lattice)
    current = Phase(
        scenario.robot.start,
        scenario.robot.heading,
        "start",
        holding=holding,
        objects={o.id: o.start for o in scenario.objects},
        clutter={c.id: c.rect.center for c in scenario.clutter},
    )
    phases = [current]
    todo = [holding] if holding is not None else []
    todo += [i for i in order if i != holding]
    while todo:
        if current.holding is None:
            todo.sort(key=lambda i: math.dist(current.objects[i], current.base))
        target = todo[0]
        leg = _one_object(scenario, space, current, target, lattice, deadline, planner)
        if leg is None:
            return None
        phases.extend(leg)
        current = phases[-1]
        todo.remove(target)
    return tuple(phases)


def _one_object(
    scenario: Scenario, space: FreeLattice, current: Phase, target: str, lattice: Lattice, deadline: Deadline,
    planner: Planner,
) -> list[Phase] | None:  # fmt: skip
    """The phases after ``current`` that deliver ``target`` (see :func:`decoupled_apart`); None if none found."""
    picked: list[Phase] = []
    if current.holding is None:
        objects3 = {k: (v[0], v[1], 0.0) for k, v in current.objects.items()}
        picked = pick_leg(space, current, target, objects3) or []
        if not picked:  # (a push first, say): moves towards the object, then the MILP for the whole delivery
            return _towards_then_plan(scenario, space, current, current.objects[target], target, lattice, deadline,
                                      planner)  # fmt: skip
    at = picked[-1] if picked else current
    rest = _towards_then_plan(scenario, space, at, scenario.object(target).goal, target, lattice, deadline, planner)
    return None if rest is None else [*picked, *rest]


def _towards_then_plan(
    scenario: Scenario, space: FreeLattice, at: Phase, point: tuple[float, float], target: str, lattice: Lattice,
    deadline: Deadline, planner: Planner,
) -> list[Phase] | None:  # fmt: skip
    """Moves from ``at`` towards ``point`` (stopping ``PLACE_KEEP`` metres of path before it), then the MILP for
    ``target`` from there; from ``at`` itself when that finds nothing; None if neither does."""
    ends = approach(space, at.base, point, PLACE_KEEP)
    for start in (moves_along(at, ends), []) if ends else ([],):
        rest = _sub_plan(scenario, start[-1] if start else at, [target], lattice, deadline, planner)
        if rest is not None:
            return [*start, *rest]
    return None


def _sub_plan(scenario, current: Phase, targets, lattice, deadline, planner) -> list[Phase] | None:
    """The single-object MILP's phases after ``current`` through its first place; None without a plan."""
    left = deadline.left()
    if left <= 0:
        raise TimeUp
    sub = _sub_problem(scenario, targets, current.base, current.heading, current.objects, current.clutter)
    # With the object in the hand (a short leg) no relaxation bound: on an apartment's lattice it outlasts the
    # leg's own solves; a whole delivery keeps it (deepening from 3 phases would prove too many counts infeasible).
    bound = current.holding is None
    result = planner(sub, time_limit=left, lattice=lattice, holding=current.holding, lower_bound=bound)
    if not result.found:
        return None
    if len(result.phases) > 2 and deadline.left() > SHORTER_SUB_PLAN_S:  # the optimal sub-plan, if it comes quickly
        limit, held = SHORTER_SUB_PLAN_S, current.holding
        shorter = planner(sub, time_limit=limit, lattice=lattice, holding=held, first=False, lower_bound=bound)
        if shorter.found and len(shorter.phases) <= len(result.phases):
            result = shorter
    kept = _through_first_place(result.phases)
    return None if kept is None else kept[1:]


def fallback_plan(
    scenario: Scenario,
    order: Sequence[str],
    lattice: Lattice,
    deadline: Deadline,
    planner: Planner,
    holding: str | None = None,
) -> Plan:
    """The decoupled plan, nearest object first, as a :class:`Plan` with status ``feasible``, or ``time_limit``.

    The answer of last resort of a caller whose planning call found no plan in time
    (:class:`expert.policy.ExpertPolicy`): one single-object MILP per object, no bound
    of the whole problem, so it comes in about a second where the whole problem's
    bounds alone outlast the time limit (eight objects). It is a valid plan, never
    claimed optimal (``stats["optimality"]``). ``planner`` should stop at its sub-plans'
    first solutions (SCIP's ``limits/solutions = 1``); each gets the time left before
    ``deadline``. ``order``: the objects still to deliver (the held one included).
    Two tries, the plan with fewer phases kept: :func:`decoupled_apart` (long legs without
    the MILP: comes in a few seconds in an apartment), then, in what is left of at most
    ``WHOLE_LEGS_S``, :func:`decoupled_plan` (the MILP for each whole delivery: fewer
    phases where the objects are a few phases apart, too slow across rooms); each without
    the moves a straight slide makes unnecessary (:func:`expert.approach.shortcut`).
    ``status`` is ``infeasible`` when some object has no single-object plan.
    """
    started = time.perf_counter()
    stats: dict[str, object] = {}
    phases, status = None, "infeasible"
    attempts = (("apart", decoupled_apart, deadline), ("whole legs", _nearest_first, None))
    for how, make, budget in attempts:
        if budget is None:  # the second try: a shorter plan, in what is left of WHOLE_LEGS_S
            budget = Deadline(min(deadline.at, time.perf_counter() + WHOLE_LEGS_S))
        try:
            found = make(scenario, order, lattice, budget, planner, holding=holding)
            found = None if found is None else carry(shortcut(scenario, found))
        except TimeUp:
            found = None
            status = status if phases is not None or budget is not deadline else "time_limit"
        if found is not None and (phases is None or len(found) < len(phases)):
            phases, status = found, "feasible"
            stats["decoupled"] = f"fallback, nearest object first, {how}"
        if deadline.left() <= 0:
            break
    stats["total_s"] = time.perf_counter() - started
    if phases is None:
        stats["optimality"] = f"no plan (status {status}), so no claim of optimality"
        return Plan(scenario.name, status, None, (), stats)
    stats["optimality"] = "not proven optimal: the decoupled plan (one object at a time, nearest first), no bound"
    stats["decoupled_phases"] = len(phases)
    return Plan(scenario.name, "feasible", plan_objective(scenario, phases), phases, stats)


def _nearest_first(scenario, order, lattice, deadline, planner, holding=None) -> tuple[Phase, ...] | None:
    return decoupled_plan(scenario, order, lattice, deadline, planner, nearest=True, holding=holding)


def _through_first_place(phases: Sequence[Phase]) -> list[Phase] | None:
    """The phases up to the first place, that one included; None if there is no place."""
    end = next((k for k, p in enumerate(phases) if p.action == "place"), None)
    return None if end is None else list(phases[: end + 1])


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
