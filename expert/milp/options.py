"""Pose options: every way the arm can pick, place or push, each with the box of bases it may act from.

The paper selects, per phase, one of ``4 x N_pos`` heading-posture pairs
(``theta_k^{fore|back|left|right, alpha}``, Eq. 14-15) at picks and places (Eq. 16-17).
We enumerate these choices per action before the solve as *pose options*
(:class:`PoseOption`): for an action (pick object i, place object i, push piece c in
direction d), a heading h and a posture alpha, the hand's point is known (the
object's start, its goal, the push contact), so the posture's ranges turn into a box
of lattice points for the base (:func:`reach_box`). The selection constraints are in
:mod:`expert.milp.postures`.

The box is cut (:func:`expert.milp.grid.split_box`) by the static parts of the rules:

- the base disc off every table and obstacle (Eq. 18 at the acting pose);
- the arm line (Eq. 19) clear of every obstacle and of clutter that never moves;
- the env's rule of which item an action takes (the object within the posture's
  ranges nearest their middle; for a push, the piece whose push contact is):
  :func:`split_by_choice` keeps the bases from which the env takes the target.

Pushable clutter moves and other objects come and go, so an option that some item
would block (the arm line) or confuse (a pick) in some position carries that
position as a *forbidden state*: ``(clutter id, "start" | direction)`` or
``(object id, "start" | "goal")``; the constraints are in
:mod:`expert.milp.collision` and :mod:`expert.milp.objects`.

Nothing here depends on the number of phases or on the solver.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import Condition, Grid, HalfPlane, IndexBox, base_regions, split_box
from expert.milp.strokes import PushCandidate, PushPlan
from fetchcarry_env import regions
from fetchcarry_env.geometry import HEADINGS, Heading, Point, Rect
from fetchcarry_env.kinematics import hand_offset, push_contact, push_headings
from fetchcarry_env.regions import hand_in_side
from fetchcarry_env.scenario import Posture, Scenario


@dataclass(frozen=True)
class PoseOption:
    """One way to do one arm action: kind, target, heading, posture and where the base may stand.

    ``box`` holds the acting base: the base of the phase for a pick or a place, the base
    where the stroke *starts* (the previous phase's) for a push. ``forbidden`` lists the
    ``(clutter id, position)`` states of pushable clutter in which the option may not be
    used: the arm line (Eq. 19) would be blocked, or (a push) the env would push that
    piece instead; ``position`` is ``"start"`` or a push direction. ``confusers`` lists
    the :class:`ObjectAt` states in which a pick would take another object.
    """

    kind: str  # "pick", "place" or "push"
    target: str  # object id (pick, place) or clutter id (push)
    heading: Heading
    posture: str
    box: IndexBox
    hand: Point  # where the hand acts: the object's start, its goal, or the push contact
    forbidden: frozenset = frozenset()
    push: PushCandidate | None = None
    confusers: frozenset = frozenset()

    @property
    def end_box(self) -> IndexBox:
        """Where the base is at the end of the option's phase (the box, moved by a push's stroke)."""
        return self.box if self.push is None else self.box.shifted(*self.push.cells)


@dataclass(frozen=True, order=True)
class ObjectAt:
    """A state of another object in which a pick option may not be used: ``where`` is "start" or "goal".

    Ordered (by object id, then ``where``) so that the model adds an option's states in a fixed order.
    """

    object_id: str
    where: str


CONFUSION_MARGIN = 2e-3  # metres: another item confuses an action when it is in reach within 1 mm (more than
# the env's reach tolerance) plus this, and at most this much farther from the middle of the ranges: conservative


def reach_box(grid: Grid, hand: Point, heading: Heading, posture: Posture, margin: float = 0.0) -> IndexBox:
    """Lattice points from which ``posture`` at ``heading`` puts the hand on ``hand`` (ranges widened by ``margin``).

    The env's reach test for lattice bases (:func:`fetchcarry_env.regions.reach_box`).
    """
    return regions.reach_box(grid.lattice, hand, heading, posture, margin)


def arm_regions(grid: Grid, rect: Rect, hands: tuple[Point, ...], cells: tuple[int, int]) -> tuple[HalfPlane, ...]:
    """Base half-planes in which the arm stays clear of ``rect`` (Eq. 19's common region).

    The base (at both ends of a stroke of ``cells``) and every hand point must lie in one
    region of ``rect``; only regions that hold every hand point are possible. The env's
    arm rule is the same test (:func:`fetchcarry_env.rules.arm_refusal`).
    """
    out = []
    for region, plane in enumerate(base_regions(grid, rect, 0.0)):
        if all(hand_in_side(rect, hand, region) for hand in hands):
            out.append(_with_stroke(plane, cells))
    return tuple(out)


def _with_stroke(plane: HalfPlane, cells: tuple[int, int]) -> HalfPlane:
    """The half-plane for a base that must satisfy ``plane`` before and after a stroke of ``cells``."""
    shift = cells[plane.axis]
    return plane if shift == 0 else plane.tighter(plane.shifted(shift))


class _Blockers:
    """The regions of every table, obstacle and piece of clutter, computed once per problem."""

    def __init__(
        self,
        scenario: Scenario,
        grid: Grid,
        pushes: PushPlan,
        deliver: tuple[str, ...],
        holding: str | None,
    ) -> None:
        radius = scenario.robot.radius
        self.grid = grid
        self.scenario = scenario
        self.pushes = pushes
        self.deliver = deliver
        self.holding = holding
        self.base = [
            base_regions(grid, r, radius) for r in (*(t.rect for t in scenario.tables), *self._obstacles(scenario))
        ]
        pushable = set(pushes.pushable)
        self.arm_static = [*self._obstacles(scenario), *(c.rect for c in scenario.clutter if c.id not in pushable)]
        self.arm_dynamic = {c: pushes.positions(c) for c in pushes.pushable}
        self.solid = [*(t.rect for t in scenario.tables), *self._obstacles(scenario)]

    @staticmethod
    def _obstacles(scenario: Scenario) -> list[Rect]:
        return [o.rect for o in scenario.obstacles]

    def conditions(self, hands: tuple[Point, ...], cells: tuple[int, int], pushed: str | None) -> list[Condition]:
        """The static rules as box conditions: the base on a side of every grown table and obstacle, the arm's."""
        out = [Condition(tuple(_with_stroke(p, cells) for p in planes)) for planes in self.base]
        out += [Condition(arm_regions(self.grid, rect, hands, cells)) for rect in self.arm_static]
        for clutter_id, positions in self.arm_dynamic.items():
            if clutter_id == pushed:
                continue
            for position, rect in positions.items():
                out.append(Condition(arm_regions(self.grid, rect, hands, cells), tag=(clutter_id, position)))
        return out

    def others(self, kind: str, target: str, direction: Heading | None) -> list[tuple[Point, object]]:
        """Where the items an action could take instead of its target may stand: ``(point, tag)``.

        Pick: every other object at its start and its goal (the hand's point is the object's
        centre); push: every other piece of clutter at each place it can stand (the point is
        its push contact along ``direction``). ``tag`` None for an item that never moves, else
        the state in which it stands there (:class:`ObjectAt`, or ``(clutter id, position)``).
        """
        out: list[tuple[Point, object]] = []
        if kind == "pick":
            for obj in self.scenario.objects:
                if obj.id == target:
                    continue
                if obj.id not in self.deliver:  # already delivered: it stays at its goal
                    out.append((obj.goal, None))
                    continue
                if obj.id != self.holding:
                    out.append((obj.start, ObjectAt(obj.id, "start")))
                out.append((obj.goal, ObjectAt(obj.id, "goal")))
        elif kind == "push":
            pushable = set(self.pushes.pushable)
            for item in self.scenario.clutter:
                if item.id == target:
                    continue
                if item.id not in pushable:
                    out.append((push_contact(item.rect, direction), None))
                    continue
                for position, rect in self.pushes.positions(item.id).items():
                    out.append((push_contact(rect, direction), (item.id, position)))
        return out


def split_by_choice(
    grid: Grid, box: IndexBox, hand: Point, heading: Heading, posture: Posture, others: list[tuple[Point, object]]
) -> list[tuple[IndexBox, frozenset]]:
    """Cut ``box`` by which item the env would take from each base: the target, or another one.

    The env picks the object within the posture's ranges nearest their middle, and pushes
    the piece whose push contact is (``fetchcarry_env.rules``). A base from which another
    item, standing at one of its places, is in reach and not farther from the middle than
    the target (with :data:`CONFUSION_MARGIN`) gets that place's tag (the option is
    forbidden while the item stands there), or is dropped if the item never moves.
    Returns boxes with their tag sets; lattice points with the same tags are merged.
    """
    tol = 1e-3 + CONFUSION_MARGIN  # wider than the env's reach (regions.in_reach): never misses an item it takes
    near = [(p, t) for p, t in others if not reach_box(grid, p, heading, posture, tol).intersect(box).empty]
    if not near:
        return [(box, frozenset())]
    groups: dict[frozenset, set[tuple[int, int]]] = {}
    for i in range(box.i_lo, box.i_hi + 1):
        for j in range(box.j_lo, box.j_hi + 1):
            base = grid.point(i, j)
            mine = math.dist(hand_offset(base, heading, hand), posture.center)
            tags: set = set()
            for point, tag in near:
                offset = hand_offset(base, heading, point)
                if posture.reaches(*offset, tol=tol) and math.dist(offset, posture.center) <= mine + CONFUSION_MARGIN:
                    tags.add(tag)
            if None not in tags:
                groups.setdefault(frozenset(tags), set()).add((i, j))
    return [(rect, tags) for tags, cells in groups.items() for rect in _rectangles(cells)]


def _rectangles(cells: set[tuple[int, int]]) -> list[IndexBox]:
    """Cover a set of lattice points by disjoint boxes, greedily (row runs grown across rows)."""
    left = set(cells)
    out = []
    while left:
        i, j = min(left)
        j_hi = j
        while (i, j_hi + 1) in left:
            j_hi += 1
        i_hi = i
        while all((i_hi + 1, jj) in left for jj in range(j, j_hi + 1)):
            i_hi += 1
        out.append(IndexBox(i, i_hi, j, j_hi))
        left -= {(ii, jj) for ii in range(i, i_hi + 1) for jj in range(j, j_hi + 1)}
    return out


def pose_options(
    scenario: Scenario,
    grid: Grid,
    deliver: tuple[str, ...],
    holding: str | None,
    pushes: PushPlan,
    deadline: Deadline = NEVER,
) -> list[PoseOption]:
    """Every pick, place and push pose option of the problem (see the module docstring); checks ``deadline``."""
    blockers = _Blockers(scenario, grid, pushes, deliver, holding)
    out: list[PoseOption] = []
    for obj in scenario.objects:
        if obj.id not in deliver:
            continue
        if obj.id != holding:
            out += _options(scenario, grid, blockers, "pick", obj.id, obj.start, None, deadline)
        out += _options(scenario, grid, blockers, "place", obj.id, obj.goal, None, deadline)
    for candidate in pushes.candidates:
        out += _options(scenario, grid, blockers, "push", candidate.clutter, candidate.contact, candidate, deadline)
    return out


def _options(
    scenario: Scenario,
    grid: Grid,
    blockers: _Blockers,
    kind: str,
    target: str,
    hand: Point,
    push: PushCandidate | None,
    deadline: Deadline = NEVER,
) -> list[PoseOption]:
    """The options of one action: every heading and posture, each box cut by the static collision rules."""
    cells = push.cells if push else (0, 0)
    hands = (
        (hand, (hand[0] + push.stroke * _sign(cells[0]), hand[1] + push.stroke * _sign(cells[1]))) if push else (hand,)
    )
    domain = grid.domain.intersect(grid.domain.shifted(-cells[0], -cells[1]))
    headings = push_headings(push.direction) if push else HEADINGS
    others = blockers.others(kind, target, push.direction if push else None)
    out = []
    for heading in headings:
        deadline.check()
        conditions = None
        for posture in scenario.robot.postures:
            box = reach_box(grid, hand, heading, posture).intersect(domain)
            if box.empty:
                continue
            if conditions is None:
                conditions = blockers.conditions(hands, cells, target if push else None)
            for piece, blocked in split_box(box, conditions):
                for part, tags in split_by_choice(grid, piece, hand, heading, posture, others):
                    forbidden = blocked | frozenset(t for t in tags if not isinstance(t, ObjectAt))
                    confusers = frozenset(t for t in tags if isinstance(t, ObjectAt))
                    out.append(PoseOption(kind, target, heading, posture.name, part, hand, forbidden, push, confusers))
    return out


def _sign(value: int) -> int:
    return (value > 0) - (value < 0)
