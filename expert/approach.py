"""Long motions without the MILP: straight moves along a searched path, and a pick found by the env's rules.

The single-object MILP is fast when the object, its goal and the base are a few phases
apart, and slow when a delivery crosses rooms (in an apartment one object needs 12
phases, and proving that 7 to 11 admit no plan took SCIP up to 100 s). The decoupled
fallback plan (:func:`expert.decoupled.fallback_plan`) therefore makes the long legs
here: a search over the free lattice points (8-connected, every ``STRIDE``-th point, the
base kept ``MARGIN`` beyond its radius from tables, obstacles and the area's edge), cut
into straight moves that the env accepts (its move rule, :func:`fetchcarry_env.rules.move_refusal`),
and a pick at the reachable lattice pose nearest along that search that the env accepts
(:func:`fetchcarry_env.rules.check_action`).
The MILP then plans only what is left near the goal (pushes and the place).

Every move keeps the heading. Units are metres.
"""

from __future__ import annotations

import dataclasses
import heapq
import math
from collections.abc import Sequence

import numpy as np

from expert.plans import Phase
from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.geometry import HEADINGS, Point, first_contact, to_world_frame
from fetchcarry_env.kinematics import hand_offset
from fetchcarry_env.observation import WorldState
from fetchcarry_env.rules import base_blockers, check_action, move_refusal
from fetchcarry_env.scenario import Scenario

STRIDE = 2  # lattice points between the searched points (0.1 m on the env's 5 cm lattice)
MARGIN = 0.05  # metres kept beyond the base's radius by the searched points and the moves between them
PICK_RADIUS = 0.9  # metres: lattice poses this close to the object are tried for the pick
_STEPS = [(di, dj) for di in (-1, 0, 1) for dj in (-1, 0, 1) if (di, dj) != (0, 0)]


class FreeLattice:
    """The lattice points (every ``STRIDE``-th) where the base stands ``MARGIN`` clear of every blocker."""

    def __init__(self, scenario: Scenario, lattice: Lattice) -> None:
        self.scenario, self.lattice = scenario, lattice
        self.blockers = [rect for _, rect in base_blockers(scenario)]
        self.bounds = np.array([(r.min_x, r.min_y, r.max_x, r.max_y) for r in self.blockers], dtype=float)
        self.clearance = scenario.robot.radius + MARGIN
        xs = lattice.axis_points(0)[::STRIDE]
        ys = lattice.axis_points(1)[::STRIDE]
        gx, gy = np.meshgrid(xs, ys, indexing="ij")
        free = np.ones(gx.shape, dtype=bool)
        for rect in self.blockers:
            dx = np.maximum(np.maximum(rect.min_x - gx, 0.0), gx - rect.max_x)
            dy = np.maximum(np.maximum(rect.min_y - gy, 0.0), gy - rect.max_y)
            free &= np.hypot(dx, dy) > self.clearance
        self.free = free

    def point(self, cell: tuple[int, int]) -> Point:
        return self.lattice.point(cell[0] * STRIDE, cell[1] * STRIDE)

    def clear(self, a: Point, b: Point, exact: bool = False) -> bool:
        """True when the env allows the move from ``a`` to ``b`` and it keeps half of ``MARGIN`` beyond the radius.

        ``exact``: by the env's own move rule alone (for a slide from a base that stands
        closer than that to a table, as at a pick).
        """
        if move_refusal(self.scenario, self.lattice, a, b) is not None:
            return False
        if exact:
            return True
        radius = self.scenario.robot.radius + MARGIN / 2
        lo_x, hi_x = min(a[0], b[0]) - radius, max(a[0], b[0]) + radius
        lo_y, hi_y = min(a[1], b[1]) - radius, max(a[1], b[1]) + radius
        bounds = self.bounds
        near = (bounds[:, 0] <= hi_x) & (bounds[:, 2] >= lo_x) & (bounds[:, 1] <= hi_y) & (bounds[:, 3] >= lo_y)
        return first_contact(a, b, radius, [self.blockers[k] for k in np.flatnonzero(near)]) >= 1.0

    def distances(self, start: Point) -> tuple[dict, dict]:
        """Path lengths (metres) from the searched points straight-line clear of ``start``, and each point's parent."""
        nx, ny = self.free.shape
        cost: dict[tuple[int, int], float] = {}
        parent: dict[tuple[int, int], tuple[int, int] | None] = {}
        queue: list[tuple[float, tuple[int, int]]] = []
        i0, j0 = (round(v / STRIDE) for v in self.lattice.index(start))
        for di in range(-3, 4):
            for dj in range(-3, 4):
                cell = (i0 + di, j0 + dj)
                inside = 0 <= cell[0] < nx and 0 <= cell[1] < ny
                if inside and self.free[cell] and self.clear(start, self.point(cell), exact=True):
                    c = math.dist(start, self.point(cell))
                    if c < cost.get(cell, math.inf):
                        cost[cell], parent[cell] = c, None
                        heapq.heappush(queue, (c, cell))
        step = self.lattice.resolution * STRIDE
        while queue:
            c, (i, j) = heapq.heappop(queue)
            if c > cost[(i, j)]:
                continue
            for di, dj in _STEPS:
                n = (i + di, j + dj)
                if not (0 <= n[0] < nx and 0 <= n[1] < ny) or not self.free[n]:
                    continue
                if di and dj and not (self.free[i + di, j] and self.free[i, j + dj]):
                    continue  # no corner cutting
                total = c + step * (math.sqrt(2.0) if di and dj else 1.0)
                if total < cost.get(n, math.inf):
                    cost[n], parent[n] = total, (i, j)
                    heapq.heappush(queue, (total, n))
        return cost, parent

    def path_to(self, parent: dict, cell: tuple[int, int]) -> list[Point]:
        """The searched points from the start's neighbour to ``cell``."""
        cells: list[tuple[int, int]] = []
        at: tuple[int, int] | None = cell
        while at is not None:
            cells.append(at)
            at = parent[at]
        return [self.point(c) for c in reversed(cells)]

    def straight_moves(self, start: Point, path: Sequence[Point]) -> list[Point]:
        """``path`` cut into straight clear moves from ``start``: the end points, the last one ``path[-1]``.

        Each move goes as far along the path as the straight line stays clear (scanning forwards).
        """
        ends: list[Point] = []
        at, k = start, 0
        while k < len(path):
            far = k
            exact = at == start  # the start may stand closer to a table than the searched points
            for m in range(k + 1, len(path)):
                if not self.clear(at, path[m], exact):
                    break
                far = m
            if not self.clear(at, path[far], exact):
                return []
            at, k = path[far], far + 1
            ends.append(at)
        return ends


def approach(space: FreeLattice, start: Point, target: Point, keep: float) -> list[Point]:
    """Straight moves from ``start`` towards the searched point nearest ``target``, ``keep`` metres of path short.

    Empty when that point is within ``keep`` of the start along the path, or none is reached.
    """
    cost, parent = space.distances(start)
    if not cost:
        return []
    nearest = min(cost, key=lambda c: (math.dist(space.point(c), target), cost[c]))
    path = space.path_to(parent, nearest)
    total = cost[nearest]
    kept = [p for p, c in zip(path, _cumulative(start, path), strict=True) if c <= total - keep]
    return space.straight_moves(start, kept) if kept else []


def _cumulative(start: Point, path: Sequence[Point]) -> list[float]:
    out, at, length = [], start, 0.0
    for p in path:
        length += math.dist(at, p)
        out.append(length)
        at = p
    return out


def pick_leg(
    space: FreeLattice,
    phase: Phase,
    target: str,
    objects3: dict[str, tuple[float, float, float]],
) -> list[Phase] | None:
    """Moves and a pick of ``target`` from ``phase`` (empty hand), the pick by the env's rules; None if none.

    The pick pose is the lattice point within ``PICK_RADIUS`` of the object, reached
    along the search with the least path length, from which some heading and posture
    pick ``target`` (and nothing else) with a clear arm line; the last straight move to it
    is checked with the env's own contact rule.
    """
    scenario, lattice = space.scenario, space.lattice
    cost, parent = space.distances(phase.base)
    spot = scenario.object(target).start if target not in objects3 else objects3[target][:2]
    near = sorted((c for c in cost if math.dist(space.point(c), spot) <= PICK_RADIUS), key=lambda c: cost[c])
    world = WorldState(phase.base, phase.heading, None, dict(objects3), dict(phase.clutter))
    for cell in near:
        around = _poses_around(lattice, space.point(cell))
        poses = [p for p in around if _pick_at(scenario, world, lattice, None, p, target)]
        if not poses:
            continue
        path = space.path_to(parent, cell)
        ends = space.straight_moves(phase.base, path[:-1]) if len(path) > 1 else []
        for pose in poses:
            found = _pick_at(scenario, world, lattice, ends[-1] if ends else phase.base, pose, target)
            if found is None:
                continue
            while ends and _pick_at(scenario, world, lattice, ends[-2] if len(ends) > 1 else phase.base, pose, target):
                ends.pop()  # the pick's own slide reaches the pose from one move earlier
            heading, posture = _pick_at(scenario, world, lattice, ends[-1] if ends else phase.base, pose, target)
            moves = moves_along(phase, ends)
            last = moves[-1] if moves else phase
            pick = Phase(pose, heading, "pick", target, posture, target, dict(last.objects), dict(last.clutter))
            return [*moves, pick]
    return None


def _poses_around(lattice: Lattice, point: Point) -> list[Point]:
    """The lattice points of the searched point's cell of ``STRIDE`` x ``STRIDE``."""
    i, j = lattice.index(point)
    return [lattice.point(i + a, j + b) for a in range(STRIDE) for b in range(STRIDE)]


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
