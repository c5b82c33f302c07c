"""Which phases are possible from a state: the environment's action checks, as pure geometry.

The environment asks :func:`check_action` before it moves anything: the answer is
either a :class:`ResolvedPhase` (what to execute: where the base goes, what the arm takes,
where the hand goes) or a short reason why the action is impossible, which the
environment reports in ``info["invalid_action"]``. :func:`action_mask` is the part of
these checks that can be said per action component (MaskablePPO's convention).

The motion and arm rules are the MILP expert's model stated exactly
(``docs/design.md``, "The env's rules are the planner's model";
:mod:`fetchcarry_env.regions` holds the geometry both use):

- **moves** (:func:`move_refusal`): a move of the base from ``p`` to ``q`` (a move
  phase, the move to a pick's or place's pose, a push stroke) is allowed when both ends
  keep the base disc inside the area and, for every table and obstacle, ``p`` and ``q``
  lie in one common region of its octagon (Eq. 18). Such a move never touches anything;
  any other is refused, not stopped at a contact;
- **acting poses** (:func:`pose_refusal`): a pick or place acts from a base that lies
  on one side of every table and obstacle grown by the radius (the square's four sides,
  not a corner cut); a push stroke keeps both its ends on one common such side;
- **the arm** (:func:`arm_refusal`, Eq. 19): for every obstacle and piece of clutter
  (but the one pushed), the base (both ends of a stroke) and the hand (both ends of a
  stroke) lie in one common side half-plane of its rectangle;
- **reach** (:func:`fetchcarry_env.regions.in_reach`): a posture reaches a point from a
  lattice base when the base lies in the planner's reach box (the posture's exact ranges
  rounded to the lattice), from another base when the offset lies within the ranges
  widened by 5e-7 m (it was 1 mm, which let the env take poses the planner does not have).

Lattice points are tested in lattice indices with the planner's exact integer bounds,
other points (the start, a base after a jammed push) in metres with its tolerance.
:func:`move_stop` is the physical test (where a sliding base first touches a table, an
obstacle or the edge of the area), which the plan validator's file format uses.

The semantics are those of :mod:`fetchcarry_env.actions` and ``docs/design.md``. Units are metres.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.geometry import HEADINGS, Heading, Point, Rect, first_contact, heading_of, heading_vector
from fetchcarry_env.kinematics import hand_blocker, hand_offset, push_contact, push_headings
from fetchcarry_env.observation import WorldState
from fetchcarry_env.regions import (
    ALL_SIDES,
    GEOM_TOL,
    area_domain,
    hand_bits,
    in_reach,
    lattice_cell,
    octagon_bits,
    side_bits,
)
from fetchcarry_env.scenario import Posture, Scenario

ALIGN_TOLERANCE = 1e-6  # metres: a stroke whose cross-axis component is below this is axis-aligned
CONTACT_SLACK = 1e-6  # metres: a base that passes this close to a blocker (docs/plan-format.md) does not touch it
EDGE_DEPTH = 1.0  # metres: thickness of the strips outside the area that stop the base at its edge
AREA_EDGE = "area edge"  # what a move that stops at the edge of the area reports it touched


@dataclass(frozen=True)
class ResolvedPhase:
    """A possible phase, resolved: what the environment executes (not a plan's :class:`expert.plans.Phase`).

    ``base`` is where the base is sent (for a push, where the stroke ends); ``target``
    the object picked or placed or the clutter pushed; ``hand`` where the hand goes
    (the object's centre, the goal, or the push contact); ``direction`` and ``stroke``
    the push stroke's direction and length (metres).
    """

    mode: Mode
    base: Point
    heading: Heading
    posture: Posture | None = None
    target: str | None = None
    hand: Point | None = None
    direction: Heading | None = None
    stroke: float = 0.0


Phase = ResolvedPhase  # the name it had first


def action_mask(scenario: Scenario, state: WorldState, lattice: Lattice, max_postures: int) -> np.ndarray:
    """The flat boolean mask of length ``nx + ny + 4 + max_postures + 4`` (MaskablePPO's convention).

    False marks what no action with that component can do: lattice columns or rows where
    the base disc does not fit in the area (:func:`fetchcarry_env.regions.area_domain`),
    postures the robot does not have, pick with a full hand, place with an empty one, push
    when there is no clutter (a push may be made with an empty hand or holding an object).
    Every component keeps at least one allowed value (``move`` always is: MaskablePPO needs one).
    """
    domain = area_domain(lattice, scenario.area, scenario.robot.radius)
    parts = []
    for axis in (0, 1):
        index = np.arange(lattice.shape[axis])
        fits = (index >= domain.lo(axis)) & (index <= domain.hi(axis))
        if not fits.any():
            fits[int(np.argmin(np.abs(lattice.axis_points(axis) - state.base[axis])))] = True
        parts.append(fits)
    parts.append(np.ones(len(HEADINGS), dtype=bool))
    parts.append(np.arange(max_postures) < len(scenario.robot.postures))
    empty = state.holding is None
    modes = np.zeros(len(Mode), dtype=bool)
    modes[[Mode.MOVE, Mode.PICK, Mode.PLACE, Mode.PUSH]] = [True, empty, not empty, bool(scenario.clutter)]
    parts.append(modes)
    return np.concatenate(parts)


def check_action(scenario: Scenario, state: WorldState, lattice: Lattice, action: Action) -> ResolvedPhase | str:
    """The phase ``action`` asks for, or a short reason why it is impossible from ``state``."""
    if not area_domain(lattice, scenario.area, scenario.robot.radius).contains(*action.cell):
        return "cell outside the area"
    if action.posture >= len(scenario.robot.postures):
        return f"no posture {action.posture}"
    posture = scenario.robot.postures[action.posture]
    target = lattice.point(*action.cell)
    if action.mode == Mode.PUSH:
        return _check_push(scenario, state, lattice, target, action.heading, posture)
    refusal = move_refusal(scenario, lattice, state.base, target)
    if refusal is not None:
        return refusal
    if action.mode == Mode.MOVE:
        return ResolvedPhase(Mode.MOVE, target, action.heading)
    if action.mode == Mode.PICK:
        phase = _check_pick(scenario, state, lattice, target, action.heading, posture)
    else:
        phase = _check_place(scenario, state, lattice, target, action.heading, posture)
    if isinstance(phase, str):
        return phase
    bases, hands = (target,), (phase.hand,)
    refusal = pose_refusal(scenario, lattice, bases) or arm_refusal(scenario, state, lattice, bases, hands)
    return phase if refusal is None else refusal


def move_blockers(scenario: Scenario) -> list[tuple[str, Rect]]:
    """What the base moves around, by id: every table and obstacle (the octagons of the move rule)."""
    return [*((t.id, t.rect) for t in scenario.tables), *((o.id, o.rect) for o in scenario.obstacles)]


def in_area(scenario: Scenario, lattice: Lattice | None, point: Point) -> bool:
    """Whether a base at ``point`` keeps its disc inside the area (Eq. 27).

    A lattice point is tested in lattice indices (:func:`~fetchcarry_env.regions.area_domain`),
    another point in metres, with the same tolerance (:data:`~fetchcarry_env.regions.GEOM_TOL`).
    """
    cell = lattice_cell(lattice, point)
    if cell is not None:
        return area_domain(lattice, scenario.area, scenario.robot.radius).contains(*cell)
    return scenario.area.contains_disc(point, scenario.robot.radius, tol=GEOM_TOL)


def move_refusal(scenario: Scenario, lattice: Lattice | None, start: Point, end: Point) -> str | None:
    """Why the base may not move from ``start`` to ``end`` (metres), or None: the move rule (Eq. 18, Eq. 27).

    Refused when an end leaves the base disc outside the area, or when, for some table or
    obstacle, no region of its octagon (:func:`fetchcarry_env.regions.octagon_regions`)
    holds both ends; the reason names that table or obstacle. An allowed move keeps the
    swept disc off every table and obstacle and inside the area. ``lattice`` None tests
    every point in metres (:func:`~fetchcarry_env.regions.lattice_cell`): never more
    lenient than the env's own test, for callers that do not know the env's lattice.
    """
    if not (in_area(scenario, lattice, start) and in_area(scenario, lattice, end)):
        return "move leaves the area"
    radius = scenario.robot.radius
    for name, rect in move_blockers(scenario):
        if not octagon_bits(lattice, rect, radius, start) & octagon_bits(lattice, rect, radius, end):
            return f"move passes {name!r}: no region of its octagon holds both ends"
    return None


def pose_refusal(scenario: Scenario, lattice: Lattice | None, bases: tuple[Point, ...]) -> str | None:
    """Why the arm may not act from ``bases`` (a pose, or a stroke's two ends), or None.

    Every table and obstacle must have one side of its rectangle grown by the radius that
    holds every base (a corner cut of its octagon does not count): the planner's poses.
    """
    radius = scenario.robot.radius
    for name, rect in move_blockers(scenario):
        common = ALL_SIDES
        for base in bases:
            common &= octagon_bits(lattice, rect, radius, base)
        if not common:
            return f"acting base in a corner zone of {name!r}: on no side of it"
    return None


def arm_refusal(
    scenario: Scenario,
    state: WorldState,
    lattice: Lattice | None,
    bases: tuple[Point, ...],
    hands: tuple[Point, ...],
    ignore: str | None = None,
) -> str | None:
    """Why the arm may not reach ``hands`` from ``bases``, or None: Eq. 19 as the planner states it.

    For every obstacle and piece of clutter (where ``state`` has it; but ``ignore``, the
    piece pushed) one side half-plane of its rectangle (``x >= max_x``, ``x <= min_x``,
    ``y >= max_y``, ``y <= min_y``) must hold every base and every hand point (bases on the
    lattice by the index test, hands with :data:`~fetchcarry_env.regions.HAND_TOL`); then
    no arm line from a base to a hand crosses it.
    """
    blockers = [(o.id, o.rect) for o in scenario.obstacles]
    blockers += [(c.id, clutter_rect(scenario, state, c.id)) for c in scenario.clutter if c.id != ignore]
    for name, rect in blockers:
        common = ALL_SIDES
        for base in bases:
            common &= side_bits(lattice, rect, base)
        for hand in hands:
            common &= hand_bits(rect, hand)
        if not common:
            return f"arm line crosses {name!r}: base and hand on no common side of it"
    return None


def move_stop(scenario: Scenario, start: Point, end: Point) -> tuple[Point, str | None]:
    """Where a base sliding from ``start`` to ``end`` stops, and what it touched (None if nothing).

    Tables, obstacles and the edge of the area stop it at the first contact
    (:func:`fetchcarry_env.geometry.first_contact`, exact: nothing tunnels). A move that
    only grazes a blocker, closer than the base's radius by at most :data:`CONTACT_SLACK`
    (the plan validator's tolerance), is free: a valid plan never touches anything.
    """
    radius = scenario.robot.radius
    swept = Rect(  # the box around every disc of the move: a blocker outside it cannot be touched
        min(start[0], end[0]) - radius,
        min(start[1], end[1]) - radius,
        max(start[0], end[0]) + radius,
        max(start[1], end[1]) + radius,
    )
    t_stop, touched = 1.0, None
    for name, rect in base_blockers(scenario):
        if not swept.overlaps_rect(rect, tol=0.0):
            continue
        if first_contact(start, end, radius - CONTACT_SLACK, (rect,)) < 1.0:
            t = first_contact(start, end, radius, (rect,))  # at most the slack test's t, so below 1
            if t < t_stop:
                t_stop, touched = t, name
    if touched is None:
        return end, None
    return (start[0] + t_stop * (end[0] - start[0]), start[1] + t_stop * (end[1] - start[1])), touched


def base_blockers(scenario: Scenario) -> list[tuple[str, Rect]]:
    """Everything the base may not touch, by id: tables, obstacles and four strips around the area."""
    area = scenario.area
    d = EDGE_DEPTH
    edges = (
        Rect(area.min_x - d, area.min_y - d, area.min_x, area.max_y + d),
        Rect(area.max_x, area.min_y - d, area.max_x + d, area.max_y + d),
        Rect(area.min_x - d, area.min_y - d, area.max_x + d, area.min_y),
        Rect(area.min_x - d, area.max_y, area.max_x + d, area.max_y + d),
    )
    return [
        *((t.id, t.rect) for t in scenario.tables),
        *((o.id, o.rect) for o in scenario.obstacles),
        *((AREA_EDGE, rect) for rect in edges),
    ]


def clutter_rect(scenario: Scenario, state: WorldState, clutter_id: str) -> Rect:
    """The footprint of a piece of clutter where ``state`` has it (axis-aligned, metres)."""
    size_x, size_y = scenario.clutter_item(clutter_id).rect.size
    return Rect.around(state.clutter[clutter_id], size_x / 2, size_y / 2)


def _nearest_in_reach(
    points: Iterable[tuple[str, Point]], lattice: Lattice, base: Point, heading: Heading, posture: Posture
) -> str | None:
    """The id of the point nearest ``posture``'s centre among those within its reach from ``base``, or None.

    Reach is the planner's (:func:`fetchcarry_env.regions.in_reach`); the hand's offset is
    measured in the robot frame of ``(base, heading)``; of a tie, the first point wins.
    """
    best, best_distance = None, math.inf
    for item_id, point in points:
        if in_reach(lattice, base, heading, posture, point):
            distance = math.dist(hand_offset(base, heading, point), posture.center)
            if distance < best_distance:
                best, best_distance = item_id, distance
    return best


def _check_pick(
    scenario: Scenario, state: WorldState, lattice: Lattice, base: Point, heading: Heading, posture: Posture
) -> ResolvedPhase | str:
    """The object a pick from ``base`` takes, or why none (the arm's rules are checked by the caller)."""
    if state.holding is not None:
        return "pick with a full hand"
    objects = ((obj.id, state.objects[obj.id][:2]) for obj in scenario.objects)
    best = _nearest_in_reach(objects, lattice, base, heading, posture)
    if best is None:
        return "nothing to pick within reach"
    return ResolvedPhase(Mode.PICK, base, heading, posture, best, state.objects[best][:2])


def _check_place(
    scenario: Scenario, state: WorldState, lattice: Lattice, base: Point, heading: Heading, posture: Posture
) -> ResolvedPhase | str:
    """The place of the held object at its goal from ``base``, or why not (the caller checks the arm's rules)."""
    if state.holding is None:
        return "place with an empty hand"
    obj = scenario.object(state.holding)
    if not in_reach(lattice, base, heading, posture, obj.goal):
        return f"goal of {obj.id!r} out of reach"
    for other in scenario.objects:
        if other.id != obj.id and math.dist(state.objects[other.id][:2], obj.goal) < other.radius + obj.radius - 1e-9:
            return f"goal of {obj.id!r} occupied by {other.id!r}"
    for item in scenario.clutter:
        if clutter_rect(scenario, state, item.id).overlaps_disc(obj.goal, obj.radius):
            return f"goal of {obj.id!r} occupied by {item.id!r}"
    return ResolvedPhase(Mode.PLACE, base, heading, posture, obj.id, obj.goal)


def _check_push(
    scenario: Scenario, state: WorldState, lattice: Lattice, end: Point, heading: Heading, posture: Posture
) -> ResolvedPhase | str:
    # The hand may be empty or hold an object (the paper's push while carrying): the held
    # object goes with the hand and touches nothing, so it neither blocks the hand nor is pushed.
    start = state.base
    dx, dy = end[0] - start[0], end[1] - start[1]
    if abs(dx) <= ALIGN_TOLERANCE:
        dx = 0.0
    if abs(dy) <= ALIGN_TOLERANCE:
        dy = 0.0
    if dx == 0.0 and dy == 0.0:
        return "push stroke of zero length"
    direction = heading_of((dx, dy))
    if direction is None:
        return "push stroke not axis-aligned"
    if heading not in push_headings(direction):
        return f"heading {heading} cannot push along {direction}"
    contacts = ((item.id, push_contact(clutter_rect(scenario, state, item.id), direction)) for item in scenario.clutter)
    best = _nearest_in_reach(contacts, lattice, start, heading, posture)
    if best is None:
        return "no clutter to push within reach"
    rect = clutter_rect(scenario, state, best)
    table = scenario.table_under_rect(rect)
    length = abs(dx) + abs(dy)
    ux, uy = heading_vector(direction)
    if table is None:
        return f"clutter {best!r} is not on a table"
    if not table.rect.contains_rect(rect.translate(ux * length, uy * length), tol=1e-6):
        return f"push would take {best!r} off {table.id!r}"
    contact = push_contact(rect, direction)
    in_the_way = hand_blocker(
        contact,
        ((c.id, clutter_rect(scenario, state, c.id)) for c in scenario.clutter if c.id != best),
        ((o.id, state.objects[o.id][:2], o.radius) for o in scenario.objects if o.id != state.holding),
    )
    if in_the_way is not None:
        return f"no room for the hand behind {best!r}: {in_the_way!r} is there"
    stroke_end = (start[0] + ux * length, start[1] + uy * length)
    hand_end = (contact[0] + ux * length, contact[1] + uy * length)
    refusal = (
        move_refusal(scenario, lattice, start, stroke_end)
        or pose_refusal(scenario, lattice, (start, stroke_end))
        or arm_refusal(scenario, state, lattice, (start, stroke_end), (contact, hand_end), ignore=best)
    )
    if refusal is not None:
        return refusal
    return ResolvedPhase(Mode.PUSH, stroke_end, heading, posture, best, contact, direction, length)
