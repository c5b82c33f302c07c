"""What the arm can reach and how the paper scores a motion: rules shared by env, planner and validator.

Pure functions on the scenario's geometry (metres), no simulator. The environment
uses them to decide whether a pick, place or push is possible before it moves
anything; the planner models the same rules as linear constraints; the plan
validator checks plans against them.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from fetchcarry_env.geometry import Heading, Point, Rect, heading_vector, segment_intersects_rect, to_robot_frame
from fetchcarry_env.scenario import Posture

HAND_HALF_SIZE = 0.02  # metres: the hand is a cube of 4 cm; a push puts its face on the clutter's rear face

WAIT_COST = 10.0  # W1 of the paper's Eq. 1: the task's cost of each phase an object is not yet at its goal
DELIVERY_BONUS = WAIT_COST  # the same W1 as Eq. 1 writes it: -W1 for each phase an object stands at its goal
DIAGONAL_WEIGHT = 0.1  # W2 of the paper's Eq. 1: weight of |dx - dy| (favours diagonal moves)
COLLISION_PENALTY = 1.0  # reward lost when the base stops at a contact
INVALID_ACTION_PENALTY = 1.0  # reward lost for an impossible (masked or failed) action


def travel_cost(start: Point, end: Point) -> float:
    """The paper's motion cost of one base move (Eq. 1-3): ``|dx| + |dy| + W2 * ||dx| - |dy||``, metres."""
    dx, dy = abs(end[0] - start[0]), abs(end[1] - start[1])
    return dx + dy + DIAGONAL_WEIGHT * abs(dx - dy)


def hand_offset(base: Point, heading: Heading, point: Point) -> tuple[float, float]:
    """Robot-frame ``(forward, lateral)`` of ``point`` seen from the base at ``heading``, metres."""
    return to_robot_frame(heading, point[0] - base[0], point[1] - base[1])


def reaches(posture: Posture, base: Point, heading: Heading, point: Point, tol: float = 1e-3) -> bool:
    """True when the hand, in ``posture``, can be put over ``point`` from the base pose."""
    return posture.reaches(*hand_offset(base, heading, point), tol=tol)


def push_contact(rect: Rect, direction: Heading) -> Point:
    """Where the hand's centre goes to push ``rect`` along ``direction``: against the middle of its rear face."""
    ux, uy = heading_vector(direction)
    cx, cy = rect.center
    half_along = (rect.max_x - rect.min_x) / 2 if ux else (rect.max_y - rect.min_y) / 2
    back = half_along + HAND_HALF_SIZE
    return (cx - ux * back, cy - uy * back)


def push_headings(direction: Heading) -> tuple[Heading, ...]:
    """Headings from which a stroke along ``direction`` is a forward or a lateral push (never backwards)."""
    ux, _uy = heading_vector(direction)
    perpendicular = ("+y", "-y") if ux else ("+x", "-x")
    return (direction, *perpendicular)


def arm_line_clear(base: Point, hand: Point, blockers: Iterable[Rect]) -> bool:
    """The paper's Eq. 19: the straight line from the base centre to the hand crosses no blocker."""
    return not any(segment_intersects_rect(base, hand, rect, tol=1e-6) for rect in blockers)


PUSH_CLEARANCE = 0.01  # metres: a pushed piece ends at least this far from the goal disc it covered


def push_stroke(rect: Rect, direction: Heading, covered: Iterable[tuple[Point, float]], resolution: float) -> float:
    """Stroke length (metres) that moves ``rect`` along ``direction`` off every covered disc ``(center, radius)``.

    The smallest whole multiple of ``resolution`` after which the rectangle keeps
    ``PUSH_CLEARANCE`` from each disc, measured along the stroke (the paper's B, per piece
    and direction). Whole multiples keep pushes exactly on the action lattice.
    """
    ux, uy = heading_vector(direction)
    needed = 0.0
    for (cx, cy), radius in covered:
        if ux:  # distance the trailing face must travel past the disc's far side
            trailing = rect.min_x if ux > 0 else -rect.max_x
            needed = max(needed, ux * cx + radius + PUSH_CLEARANCE - trailing)
        else:
            trailing = rect.min_y if uy > 0 else -rect.max_y
            needed = max(needed, uy * cy + radius + PUSH_CLEARANCE - trailing)
    return math.ceil(needed / resolution - 1e-9) * resolution


def swept_rect(rect: Rect, direction: Heading, stroke: float) -> Rect:
    """The floor the rectangle covers while it slides ``stroke`` metres along ``direction``."""
    ux, uy = heading_vector(direction)
    moved = rect.translate(ux * stroke, uy * stroke)
    return Rect(
        min(rect.min_x, moved.min_x),
        min(rect.min_y, moved.min_y),
        max(rect.max_x, moved.max_x),
        max(rect.max_y, moved.max_y),
    )


def hand_blocker(
    contact: Point,
    clutter: Iterable[tuple[str, Rect]],
    objects: Iterable[tuple[str, Point, float]],
    tol: float = 1e-6,
) -> str | None:
    """The id of a piece of clutter or an object that leaves no room for the hand at a push contact, or None.

    The hand is a cube of ``2 * HAND_HALF_SIZE`` centred on ``contact``; ``clutter`` gives
    ``(id, footprint)`` and ``objects`` ``(id, centre, radius)`` of everything else standing
    there (metres). Overlaps of ``tol`` or less do not count.
    """
    hand = Rect.around(contact, HAND_HALF_SIZE, HAND_HALF_SIZE)
    for item_id, rect in clutter:
        if rect.overlaps_rect(hand, tol=tol):
            return item_id
    for item_id, center, radius in objects:
        if hand.overlaps_disc(center, radius, tol=tol):
            return item_id
    return None
