"""Can every piece of clutter on a goal be pushed off it? The paper's s/o/q preprocessing as one test.

:meth:`fetchcarry_env.families.Family.sample` draws again a layout where some piece cannot be
pushed in any direction (the planner would find the scenario infeasible).
"""

from __future__ import annotations

import numpy as np

from fetchcarry_env.geometry import HEADINGS, Heading, Point, Rect, heading_vector, to_world_frame
from fetchcarry_env.kinematics import hand_blocker, push_contact, push_headings, push_stroke, reaches, swept_rect
from fetchcarry_env.reachability import FreeSpace
from fetchcarry_env.scenario import Clutter, Posture, Scenario

PUSH_RESOLUTION = 0.05  # metres: the default lattice; strokes are checked on it


def pushes_possible(scenario: Scenario) -> bool:
    """Every piece of clutter on a goal can be pushed off it in at least one direction."""
    space: FreeSpace | None = None
    for item in scenario.clutter:
        covered = [(o.goal, o.radius) for o in scenario.objects if item.rect.overlaps_disc(o.goal, o.radius)]
        if not covered:
            continue
        space = space or FreeSpace(scenario)
        if not any(_push_works(scenario, space, item, direction, covered) for direction in HEADINGS):
            return False
    return True


def _push_works(
    scenario: Scenario, space: FreeSpace, item: Clutter, direction: Heading, covered: list[tuple[Point, float]]
) -> bool:
    """The paper's s/o/q preprocessing as one test.

    The push stays on the table, sweeps over nothing else, and some base pose reaches its contact.
    """
    stroke = push_stroke(item.rect, direction, covered, PUSH_RESOLUTION)
    swept = swept_rect(item.rect, direction, stroke)
    table = scenario.table_under_rect(item.rect)
    if table is None or not table.rect.contains_rect(swept):
        return False
    others = [c.rect for c in scenario.clutter if c.id != item.id]
    discs = [(o.start, o.radius) for o in scenario.objects] + [(o.goal, o.radius) for o in scenario.objects]
    if any(swept.overlaps_rect(r) for r in others):
        return False
    if any(swept.overlaps_disc(c, r) and not item.rect.overlaps_disc(c, r) for c, r in discs):
        return False
    contact = push_contact(item.rect, direction)
    if not _hand_fits(scenario, item, contact):
        return False
    ux, uy = heading_vector(direction)
    for heading in push_headings(direction):
        for posture in scenario.robot.postures:
            for base in _bases_reaching(contact, heading, posture):
                end = (base[0] + ux * stroke, base[1] + uy * stroke)
                hand_end = (contact[0] + ux * stroke, contact[1] + uy * stroke)
                if (
                    space.reachable(base)
                    and space.reachable(end)
                    and reaches(posture, base, heading, contact)
                    and _arm_clear_through_stroke(scenario, item, (base, end, contact, hand_end))
                ):
                    return True
    return False


def _hand_fits(scenario: Scenario, item: Clutter, contact: Point) -> bool:
    """The hand (a cube of ``2 * HAND_HALF_SIZE`` at the push contact) overlaps no other clutter and no object.

    The environment refuses a push without room for the hand behind the piece.
    """
    others = ((c.id, c.rect) for c in scenario.clutter if c.id != item.id)
    return hand_blocker(contact, others, ((o.id, o.start, o.radius) for o in scenario.objects), tol=0.0) is None


def _arm_clear_through_stroke(scenario: Scenario, item: Clutter, points: tuple[Point, ...]) -> bool:
    """Eq. 19 through a push (the paper's q), as the planner models it.

    The bases and hands at both ends of the stroke lie on one side of every obstacle and
    every other piece of clutter, so the arm sweeps across none of them.
    """
    blockers = [o.rect for o in scenario.obstacles] + [c.rect for c in scenario.clutter if c.id != item.id]
    return all(_one_side(rect, points) for rect in blockers)


def _one_side(rect: Rect, points: tuple[Point, ...]) -> bool:
    return (
        all(x >= rect.max_x for x, _ in points)
        or all(x <= rect.min_x for x, _ in points)
        or all(y >= rect.max_y for _, y in points)
        or all(y <= rect.min_y for _, y in points)
    )


def _bases_reaching(point: Point, heading: Heading, posture: Posture) -> list[Point]:
    """Base positions from which ``posture`` at ``heading`` puts the hand on ``point`` (narrowed ranges)."""
    lateral = (posture.lateral[0] + posture.lateral[1]) / 2
    out = []
    for forward in np.linspace(posture.forward[0] + 0.03, posture.forward[1] - 0.03, 4):
        dx, dy = to_world_frame(heading, float(forward), lateral)
        out.append((point[0] - dx, point[1] - dy))
    return out
