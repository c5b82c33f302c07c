"""A fast first plan: deliver the objects one at a time, each by the single-object MILP.

The decoupled plan solves, object after object, the planner's own MILP for that one
object from where the previous delivery left the robot (the other objects standing
where they are, as if delivered; pushed clutter where it was pushed). Single-object
models solve in tens of milliseconds, so the whole plan comes quickly. It is a valid
plan of the full problem (every sub-plan obeys the same rules, and the state carries
over exactly), usually with as many phases as the optimum or a few more, and a
higher task cost. :func:`expert.planner.plan` makes them as first plans: the answer of last
resort (status ``feasible``) and, when one has no more phases than the model being solved,
SCIP's first incumbent (:mod:`expert.milp.warm`). Every sub-plan is a planning call within
a counted budget (SCIP nodes), so a decoupled plan is the same at any load.

Units are metres.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence

from expert.approach import Routes, carry, fewest_moves_order, moves_along, pick_leg, shortcut
from expert.milp.decode import SolvedPhase
from expert.milp.problem import Problem
from expert.plans import Phase, Plan, task_cost
from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import Scenario

Planner = Callable[..., Plan]
"""``planner(scenario, holding=None, lower_bound=True, optimal=False) -> Plan``: a sub-plan within its node budget.

``optimal`` False may stop at SCIP's first solution; ``lower_bound`` starts the phase counts at the
relaxation's bound. It raises :class:`~expert.milp.deadline.TimeUp` when the caller's safety stop came.
"""
PLACE_KEEP = 1.0  # metres from the goal within which the fallback's moves stop and the MILP takes over


def decoupled_plan(
    scenario: Scenario,
    order: Sequence[str],
    lattice: Lattice,
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
    ``planner`` makes each sub-plan (:data:`Planner`; passed in to avoid an import circle).
    ``holding``: an object already in the hand at the start; it is delivered first.
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
            targets = (todo[first:] + todo[:first])[: 1 if holding is not None else lookahead]
            sub = _sub_problem(scenario, targets, base, heading, objects, clutter)
            result = planner(sub, holding=holding)
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
    planner: Planner,
    holding: str | None = None,
) -> tuple[Phase, ...] | None:
    """The decoupled plan, in the order of fewest moves between deliveries
    (:func:`expert.approach.fewest_moves_order`), with the long legs made by :mod:`expert.approach`; None if it fails.

    Per object: the fewest moves to a pick the env's rules accept
    (:func:`expert.approach.pick_leg`; when none is found, moves towards the object and
    the single-object MILP for the whole delivery from there, as :func:`decoupled_plan`),
    then the fewest moves to within ``PLACE_KEEP`` metres of the goal, and the
    single-object MILP with the object in the hand for what is left (pushes, the place; from the pick when that fails).
    ``planner`` takes ``optimal=True`` for an optimal sub-plan (it may stop at SCIP's first
    solution otherwise): tried after a first solution of more than one step, and kept
    when it costs less.
    """
    routes = Routes(scenario, lattice)
    current = Phase(
        scenario.robot.start,
        scenario.robot.heading,
        "start",
        holding=holding,
        objects={o.id: o.start for o in scenario.objects},
        clutter={c.id: c.rect.center for c in scenario.clutter},
    )
    phases = [current]
    jobs = {i: (current.objects[i], scenario.object(i).goal) for i in order if i != holding}
    start = scenario.object(holding).goal if holding is not None else current.base
    todo = ([holding] if holding is not None else []) + fewest_moves_order(routes, start, jobs)
    for target in todo:
        leg = _one_object(scenario, routes, current, target, lattice, planner)
        if leg is None:
            return None
        phases.extend(leg)
        current = phases[-1]
    return tuple(phases)


def _one_object(
    scenario: Scenario, routes: Routes, current: Phase, target: str, lattice: Lattice, planner: Planner
) -> list[Phase] | None:
    """The phases after ``current`` that deliver ``target`` (see :func:`decoupled_apart`); None if none found."""
    picked: list[Phase] = []
    if current.holding is None:
        objects3 = {k: (v[0], v[1], 0.0) for k, v in current.objects.items()}
        picked = pick_leg(routes, current, target, objects3) or []
        if not picked:  # (a push first, say): moves towards the object, then the MILP for the whole delivery
            return _towards_then_plan(scenario, routes, current, current.objects[target], target, lattice, planner)
    at = picked[-1] if picked else current
    rest = _towards_then_plan(scenario, routes, at, scenario.object(target).goal, target, lattice, planner)
    return None if rest is None else [*picked, *rest]


def _towards_then_plan(
    scenario: Scenario, routes: Routes, at: Phase, point: tuple[float, float], target: str, lattice: Lattice,
    planner: Planner,
) -> list[Phase] | None:  # fmt: skip
    """The fewest moves from ``at`` to within ``PLACE_KEEP`` metres of ``point``, then the MILP for
    ``target`` from there; from ``at`` itself when that finds nothing; None if neither does."""
    ends = routes.towards(at.base, point, PLACE_KEEP)
    for start in (moves_along(at, ends), []) if ends else ([],):
        rest = _sub_plan(scenario, start[-1] if start else at, [target], planner)
        if rest is not None:
            return [*start, *rest]
    return None


def _sub_plan(scenario: Scenario, current: Phase, targets: Sequence[str], planner: Planner) -> list[Phase] | None:
    """The single-object MILP's phases after ``current`` through its first place; None without a plan."""
    sub = _sub_problem(scenario, targets, current.base, current.heading, current.objects, current.clutter)
    # With the object in the hand (a short leg) no relaxation bound: on an apartment's lattice it outlasts the
    # leg's own solves; a whole delivery keeps it (deepening from 3 phases would prove too many counts infeasible).
    bound = current.holding is None
    result = planner(sub, holding=current.holding, lower_bound=bound)
    if not result.found:
        return None
    if len(result.phases) > 2:  # more than one step: the optimal sub-plan, within its budget
        better = planner(sub, holding=current.holding, lower_bound=bound, optimal=True)
        if better.found and task_cost(sub, better.phases) < task_cost(sub, result.phases) - 1e-9:
            result = better
    kept = _through_first_place(result.phases)
    return None if kept is None else kept[1:]


def fallback_plan(
    scenario: Scenario,
    order: Sequence[str],
    lattice: Lattice,
    planner: Planner,
    holding: str | None = None,
) -> Plan:
    """The decoupled plan (one object at a time) as a :class:`Plan` with status ``feasible``, or ``infeasible``.

    The answer of last resort of a caller whose planning call found no plan within its
    budget (:class:`expert.policy.ExpertPolicy`): one single-object MILP per object, no bound
    of the whole problem. It is a valid plan, never claimed optimal (``stats["optimality"]``).
    ``order``: the objects still to deliver (the held one included). Two tries, the plan with
    fewer phases kept (the likelier to fit an episode's steps), the cheaper of two as long:
    :func:`decoupled_apart` (the order of fewest moves between deliveries and the long legs
    without the MILP: comes in a few seconds in an apartment), then :func:`decoupled_plan`
    (nearest object first, the MILP for each whole delivery: fewer
    phases where the objects are a few phases apart); each without the moves a straight
    slide makes unnecessary (:func:`expert.approach.shortcut`). Both are budgeted by the
    sub-plans' node limits, so the answer is the same at any load. ``status`` is
    ``infeasible`` when some object has no single-object plan.
    """
    stats: dict[str, object] = {}
    phases = None
    tries = (
        ("fewest moves between deliveries, apart", decoupled_apart),
        ("nearest object first, whole legs", _nearest_first),
    )
    for how, make in tries:
        found = make(scenario, order, lattice, planner, holding=holding)
        found = None if found is None else carry(shortcut(scenario, found))
        if found is not None and (phases is None or _shorter(scenario, found, phases)):
            phases = found
            stats["decoupled"] = f"fallback, {how}"
    if phases is None:
        stats["optimality"] = "no plan (status infeasible), so no claim of optimality"
        return Plan(scenario.name, "infeasible", None, (), stats)
    stats["optimality"] = "not proven optimal: the decoupled plan (one object at a time), no bound"
    stats["decoupled_phases"] = len(phases)
    return Plan(scenario.name, "feasible", task_cost(scenario, phases), phases, stats)


def _shorter(scenario: Scenario, phases: tuple[Phase, ...], than: tuple[Phase, ...]) -> bool:
    """Fewer phases, or as many and a lower task cost."""
    if len(phases) != len(than):
        return len(phases) < len(than)
    return task_cost(scenario, phases) < task_cost(scenario, than) - 1e-9


def _nearest_first(scenario, order, lattice, planner, holding=None) -> tuple[Phase, ...] | None:
    return decoupled_plan(scenario, order, lattice, planner, nearest=True, holding=holding)


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
