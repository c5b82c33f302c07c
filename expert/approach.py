"""Long motions without the MILP: the fewest straight moves the env's move rule allows, and a pick found by its rules.

The single-object MILP is fast when the object, its goal and the base are a few phases
apart, and slow when a delivery crosses rooms (in an apartment one object needs 12
phases, and proving that 7 to 11 admit no plan took SCIP up to 100 s). The decoupled
fallback plan (:func:`expert.decoupled.fallback_plan`) therefore makes the long legs
here: the least number of straight moves between two places is a breadth-first search on
the octagon-region signatures of the lattice points (:class:`expert.milp.moves.LeastMoves`,
the env's own move rule: points of one signature reach the same points in one move), and
a route of that many moves picks, signature by signature, the lattice point that keeps the
travel short (:class:`Routes`). A pick is made at the pose nearest in moves from which the env
accepts it (:func:`fetchcarry_env.rules.check_action`). The MILP then plans only what is
left near the goal (pushes and the place).

Every move keeps the heading. Units are metres.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from expert.milp.moves import UNREACHABLE, LeastMoves, geometry_moves
from expert.plans import Phase
from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.geometry import HEADINGS, Point, first_contact, to_world_frame
from fetchcarry_env.kinematics import hand_offset
from fetchcarry_env.observation import WorldState
from fetchcarry_env.regions import area_domain
from fetchcarry_env.rules import base_blockers, check_action, move_blockers, move_refusal
from fetchcarry_env.scenario import Scenario

PICK_RADIUS = 0.9  # metres: lattice poses this close to the object are tried for the pick


class Routes:
    """The fewest straight moves between the base and the lattice points of one scenario (the module docstring)."""

    def __init__(self, scenario: Scenario, lattice: Lattice) -> None:
        self.scenario, self.lattice = scenario, lattice
        radius = scenario.robot.radius
        rects = tuple(rect for _, rect in move_blockers(scenario))
        self.moves: LeastMoves = geometry_moves(lattice, area_domain(lattice, scenario.area, radius), rects, radius)
        domain = self.moves.domain
        cells = np.argwhere(self.moves.cell >= 0)  # the free lattice points, domain-relative
        self.signature = self.moves.cell[cells[:, 0], cells[:, 1]]
        self.cells = cells + np.array([domain.i_lo, domain.j_lo])  # lattice indices
        self.x = lattice.origin[0] + self.cells[:, 0] * lattice.resolution
        self.y = lattice.origin[1] + self.cells[:, 1] * lattice.resolution

    @property
    def usable(self) -> bool:
        """Whether the signature graph was built (not for thousands of obstacles: no route then)."""
        return self.moves.joined is not None

    def point(self, n: int) -> Point:
        """Free lattice point number ``n``, metres."""
        return (float(self.x[n]), float(self.y[n]))

    def least(self, start: Point) -> np.ndarray:
        """``(N,)``: the least moves from ``start`` to each free lattice point (0 at ``start`` itself)."""
        out = self.moves.from_point(start)[self.signature]
        out[(np.abs(self.x - start[0]) < 1e-9) & (np.abs(self.y - start[1]) < 1e-9)] = 0
        return out

    def near(self, point: Point, radius: float) -> np.ndarray:
        """The numbers of the free lattice points within ``radius`` metres of ``point``."""
        return np.flatnonzero(np.hypot(self.x - point[0], self.y - point[1]) <= radius)

    def region(self, point: Point, radius: float = PICK_RADIUS) -> np.ndarray:
        """The signatures of the free lattice points within ``radius`` metres of ``point``."""
        return np.unique(self.signature[self.near(point, radius)])

    def route(self, start: Point, end: int) -> list[Point] | None:
        """The ends of the fewest straight moves from ``start`` to free point ``end`` (the last is its point).

        Each move goes to a point of a signature on a shortest chain (fewest moves to the
        end's signature), the one that keeps the travel so far plus the straight line to the
        end least. None when no number of moves joins them (or without the graph).
        """
        if not self.usable:
            return None
        goal = self.point(end)
        moves = int(self.least(start)[end])
        if moves >= UNREACHABLE:
            return None
        if moves == 0:
            return []
        from_start = self.moves.from_point(start)
        to_end = self.moves.least_from(np.array([self.signature[end]]))
        ends, here = [], None  # here: the signature of the last end (None: the start)
        at = start
        for k in range(1, moves):
            on_chain = (from_start == k) & (to_end == moves - k)
            if here is not None:
                on_chain &= self.moves.joined[here]
            points = np.flatnonzero(on_chain[self.signature])
            x, y = self.x[points], self.y[points]
            length = np.hypot(x - at[0], y - at[1]) + np.hypot(x - goal[0], y - goal[1])
            n = int(points[np.argmin(length)])
            at, here = self.point(n), int(self.signature[n])
            ends.append(at)
        ends.append(goal)
        return ends

    def towards(self, start: Point, target: Point, radius: float) -> list[Point]:
        """The fewest moves from ``start`` to a free point within ``radius`` of ``target`` (the nearest of those
        that take fewest); empty when the start is within it, or none is reached."""
        if math.dist(start, target) <= radius or not self.usable:
            return []
        near = self.near(target, radius)
        least = self.least(start)[near]
        if not len(near) or least.min() >= UNREACHABLE:
            return []
        fewest = near[least == least.min()]
        end = int(fewest[np.argmin(np.hypot(self.x[fewest] - target[0], self.y[fewest] - target[1]))])
        return self.route(start, end) or []


MAX_ORDERED = 10  # objects up to which fewest_moves_order tries every order (a dynamic programme on subsets)


def fewest_moves_order(routes: Routes, start: Point, jobs: dict[str, tuple[Point, Point]]) -> list[str]:
    """The delivery order of ``jobs`` (id: object's start, goal) with the fewest moves between deliveries.

    The moves counted are the least from ``start`` to within ``PICK_RADIUS`` of the first
    object, and from within it of each goal to within it of the next object (a delivery's
    own moves are the same in any order); ties go to the shorter straight-line tour.
    Exact up to ``MAX_ORDERED`` objects, the nearest in moves next beyond.
    """
    ids = list(jobs)
    if len(ids) <= 1 or not routes.usable:
        return ids
    near = {i: routes.region(jobs[i][0]) for i in ids}
    goal = {i: routes.region(jobs[i][1]) for i in ids}
    from_start = routes.moves.from_point(start)

    def first(i: str) -> tuple[int, float]:
        return int(from_start[near[i]].min(initial=UNREACHABLE)), math.dist(start, jobs[i][0])

    def between(i: str, j: str) -> tuple[int, float]:
        return routes.moves.between(goal[i], near[j]), math.dist(jobs[i][1], jobs[j][0])

    def plus(a: tuple[int, float], b: tuple[int, float]) -> tuple[int, float]:
        return a[0] + b[0], a[1] + b[1]

    if len(ids) > MAX_ORDERED:
        order = [min(ids, key=first)]
        while len(order) < len(ids):
            order.append(min((j for j in ids if j not in order), key=lambda j: between(order[-1], j)))
        return order
    best: dict[tuple[int, int], tuple[tuple[int, float], int]] = {}  # (visited mask, last): (cost, previous last)
    for k, i in enumerate(ids):
        best[(1 << k, k)] = (first(i), -1)
    for mask in range(1, 1 << len(ids)):
        for last in range(len(ids)):
            if (mask, last) not in best:
                continue
            cost = best[(mask, last)][0]
            for k in range(len(ids)):
                if mask & (1 << k):
                    continue
                key, value = (mask | (1 << k), k), plus(cost, between(ids[last], ids[k]))
                if key not in best or value < best[key][0]:
                    best[key] = (value, last)
    full = (1 << len(ids)) - 1
    last = min(range(len(ids)), key=lambda k: best[(full, k)][0])
    order, mask = [], full
    while last >= 0:
        order.append(ids[last])
        mask, last = mask & ~(1 << last), best[(mask, last)][1]
    return order[::-1]


def pick_leg(
    routes: Routes,
    phase: Phase,
    target: str,
    objects3: dict[str, tuple[float, float, float]],
) -> list[Phase] | None:
    """Moves and a pick of ``target`` from ``phase`` (empty hand), the pick by the env's rules; None if none.

    The pick pose is the free lattice point within ``PICK_RADIUS`` of the object, fewest
    moves away (then nearest the object), from which some heading and posture pick
    ``target`` (and nothing else) with a clear arm line; the pick's own slide into it is
    checked with the env's rules.
    """
    scenario, lattice = routes.scenario, routes.lattice
    if not routes.usable:
        return None
    spot = scenario.object(target).start if target not in objects3 else objects3[target][:2]
    near = routes.near(spot, PICK_RADIUS)
    least = routes.least(phase.base)[near]
    distance = np.hypot(routes.x[near] - spot[0], routes.y[near] - spot[1])
    world = WorldState(phase.base, phase.heading, None, dict(objects3), dict(phase.clutter))
    for n in near[np.lexsort((distance, least))]:
        pose = routes.point(int(n))
        if not _pick_at(scenario, world, lattice, None, pose, target):
            continue
        route = routes.route(phase.base, int(n))
        if route is None:
            break  # the rest are no nearer in moves: none reached
        ends = route[:-1]  # the pick's own slide makes the last move
        if _pick_at(scenario, world, lattice, ends[-1] if ends else phase.base, pose, target) is None:
            continue
        while ends and _pick_at(scenario, world, lattice, ends[-2] if len(ends) > 1 else phase.base, pose, target):
            ends.pop()  # the pick's own slide reaches the pose from one move earlier
        heading, posture = _pick_at(scenario, world, lattice, ends[-1] if ends else phase.base, pose, target)
        moves = moves_along(phase, ends)
        last = moves[-1] if moves else phase
        pick = Phase(pose, heading, "pick", target, posture, target, dict(last.objects), dict(last.clutter))
        return [*moves, pick]
    return None


def _pick_at(scenario, world, lattice, before: Point | None, pose: Point, target: str) -> tuple[str, str] | None:
    """The (heading, posture name) picking ``target`` at ``pose`` after a clear slide from ``before``, or None.

    ``before`` None: the pick alone, whatever the slide to ``pose``.
    """
    world = dataclasses.replace(world, base=pose if before is None else before)  # the env's rules: the move from there
    cell = lattice.index(pose)
    for heading in HEADINGS:
        for k, posture in enumerate(scenario.robot.postures):
            outcome = check_action(scenario, world, lattice, Action(cell, heading, k, Mode.PICK))
            if not isinstance(outcome, str) and outcome.target == target:
                return heading, posture.name
    return None


def _moved(phase: Phase, end: Point) -> Phase:
    """A move of the base to ``end`` keeping the heading; a held object moves with the base."""
    dx, dy = end[0] - phase.base[0], end[1] - phase.base[1]
    objects = dict(phase.objects)
    if phase.holding is not None and phase.holding in objects:
        x, y = objects[phase.holding][:2]
        objects[phase.holding] = (x + dx, y + dy)
    return Phase(end, phase.heading, "move", None, None, phase.holding, objects, dict(phase.clutter))


SHORTCUT_MARGIN = 0.01  # metres beyond the base's radius that a move dropped by shortcut() leaves clear


def shortcut(scenario: Scenario, phases: Sequence[Phase]) -> tuple[Phase, ...]:
    """``phases`` without the moves that the next phase's own slide makes unnecessary.

    A move followed by a move, a pick or a place (whose arm acts from the phase's own
    base) is dropped when the straight slide from the phase before it to the next one's
    base stays ``SHORTCUT_MARGIN`` clear of every blocker and the env's move rule allows it
    (tested in metres, :func:`fetchcarry_env.rules.move_refusal` without a lattice); a
    move before a push is kept (the push starts where that move ends). Nothing else
    changes: moves move no item but the held object, which goes with the base.
    """
    blockers = [rect for _, rect in base_blockers(scenario)]
    radius = scenario.robot.radius + SHORTCUT_MARGIN
    out = list(phases)
    k = 1
    while k < len(out) - 1:
        here, after = out[k], out[k + 1]
        droppable = here.action == "move" and after.action in ("move", "pick", "place")
        if (
            droppable
            and first_contact(out[k - 1].base, after.base, radius, blockers) >= 1.0
            and move_refusal(scenario, None, out[k - 1].base, after.base) is None
        ):
            del out[k]
            continue
        k += 1
    return tuple(out)


def carry(phases: Sequence[Phase]) -> tuple[Phase, ...]:
    """``phases`` with the held object where the hand holds it: at the robot-frame offset it was picked with.

    The plan's record of a held object (its phases' ``objects``) is bookkeeping (the
    expert never compares a held object with the plan), but a plan file must have it
    right (:func:`expert.validate.validate_plan`, rule 7); a sub-plan solved with the
    object already in the hand does not know that offset.
    """
    out: list[Phase] = []
    held, offset = None, None
    for phase in phases:
        if phase.action == "pick" or (not out and phase.holding is not None):
            held = phase.target if phase.action == "pick" else phase.holding
            offset = hand_offset(phase.base, phase.heading, phase.objects[held][:2])
        elif held is not None and phase.holding == held and phase.action != "place":
            dx, dy = to_world_frame(phase.heading, *offset)
            hand = (phase.base[0] + dx, phase.base[1] + dy)
            phase = dataclasses.replace(phase, objects={**phase.objects, held: hand})
        if phase.action == "place":
            held = offset = None
        out.append(phase)
    return tuple(out)


def moves_along(phase: Phase, ends: Sequence[Point]) -> list[Phase]:
    """The move phases to ``ends`` in turn from ``phase``."""
    out: list[Phase] = []
    for end in ends:
        phase = _moved(phase, end)
        out.append(phase)
    return out
