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
- for a pick, the env's rule of which object a pick takes (the one within the
  posture's ranges nearest their middle): the base must not have another object
  within the ranges, so the pick takes its target whatever the order.

Pushable clutter moves and other objects come and go, so an option that some item
would block (the arm line) or confuse (a pick) in some position carries that
position as a *forbidden state*: ``(clutter id, "start" | direction)`` or
``(object id, "start" | "goal")``; the constraints are in
:mod:`expert.milp.collision` and :mod:`expert.milp.objects`.

Nothing here depends on the number of phases or on the solver.
"""

from __future__ import annotations

from dataclasses import dataclass

from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import Condition, Grid, HalfPlane, IndexBox, base_regions, split_box
from expert.milp.strokes import PushCandidate, PushPlan
from fetchcarry_env.geometry import HEADINGS, Heading, Point, Rect, to_world_frame
from fetchcarry_env.kinematics import push_contact, push_headings
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


@dataclass(frozen=True)
class ObjectAt:
    """A state of another object in which a pick option may not be used: ``where`` is "start" or "goal"."""

    object_id: str
    where: str


HAND_TOL = 5e-7  # metres: a hand point this close to a region counts as inside (float32 observations)
CONFUSION_MARGIN = 3e-3  # metres: another item counts as in reach this far outside the ranges (the env's
# reach tolerance is 1 mm; the rest covers float32 observations), so the env never takes it instead


def reach_box(grid: Grid, hand: Point, heading: Heading, posture: Posture, margin: float = 0.0) -> IndexBox:
    """Lattice points from which ``posture`` at ``heading`` puts the hand on ``hand`` (ranges widened by ``margin``)."""
    offsets = [to_world_frame(heading, f, lat) for f in posture.forward for lat in posture.lateral]
    dxs, dys = [o[0] for o in offsets], [o[1] for o in offsets]
    return grid.box_between(
        (hand[0] - max(dxs) - margin, hand[1] - max(dys) - margin),
        (hand[0] - min(dxs) + margin, hand[1] - min(dys) + margin),
    )


def out_of_reach(grid: Grid, point: Point, heading: Heading, posture: Posture, tag: object = None) -> Condition | None:
    """The base keeps ``point`` out of the posture's reach (with :data:`CONFUSION_MARGIN`), or None if it always does.

    Outside a box is a union of four half-planes, the same shape as a region of Eq. 18.
    """
    box = reach_box(grid, point, heading, posture, CONFUSION_MARGIN)
    if box.empty:
        return None
    planes = (
        HalfPlane(0, True, box.i_lo - 1),
        HalfPlane(0, False, box.i_hi + 1),
        HalfPlane(1, True, box.j_lo - 1),
        HalfPlane(1, False, box.j_hi + 1),
    )
    return Condition(planes, tag)


def arm_regions(grid: Grid, rect: Rect, hands: tuple[Point, ...], cells: tuple[int, int]) -> tuple[HalfPlane, ...]:
    """Base half-planes in which the arm stays clear of ``rect`` (Eq. 19's common region).

    The base (at both ends of a stroke of ``cells``) and every hand point must lie in one
    region of ``rect``; only regions that hold every hand point are possible.
    """
    out = []
    for region, plane in enumerate(base_regions(grid, rect, 0.0)):
        if all(_hand_in(rect, hand, region) for hand in hands):
            out.append(_with_stroke(plane, cells))
    return tuple(out)


def _hand_in(rect: Rect, hand: Point, region: int) -> bool:
    x, y = hand
    return (
        x >= rect.max_x - HAND_TOL,
        x <= rect.min_x + HAND_TOL,
        y >= rect.max_y - HAND_TOL,
        y <= rect.min_y + HAND_TOL,
    )[region]


def _with_stroke(plane: HalfPlane, cells: tuple[int, int]) -> HalfPlane:
    """The half-plane for a base that must satisfy ``plane`` before and after a stroke of ``cells``."""
    shift = cells[plane.axis]
    return plane if shift == 0 else plane.tighter(plane.shifted(shift))


class _Blockers:
    """The regions of every table, obstacle and piece of clutter, computed once per problem."""

    def __init__(
        self, scenario: Scenario, grid: Grid, pushes: PushPlan, deliver: tuple[str, ...], holding: str | None
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

    @staticmethod
    def _obstacles(scenario: Scenario) -> list[Rect]:
        return [o.rect for o in scenario.obstacles]

    def conditions(self, hands: tuple[Point, ...], cells: tuple[int, int], pushed: str | None) -> list[Condition]:
        out = [Condition(tuple(_with_stroke(p, cells) for p in planes)) for planes in self.base]
        out += [Condition(arm_regions(self.grid, rect, hands, cells)) for rect in self.arm_static]
        for clutter_id, positions in self.arm_dynamic.items():
            if clutter_id == pushed:
                continue
            for position, rect in positions.items():
                out.append(Condition(arm_regions(self.grid, rect, hands, cells), tag=(clutter_id, position)))
        return out

    def confusions(self, kind: str, target: str, heading: Heading, posture: Posture, push: PushCandidate | None):
        """The env's choice of item: no other object (pick) or piece of clutter (push) within the ranges.

        The env picks the object within the posture's ranges nearest their middle, and pushes
        the piece whose push contact is (``fetchcarry_env.rules``); with no other one in
        reach, it takes the target. Items that never move give plain conditions, the others
        one tagged condition per place they can stand (the option is forbidden while they do).
        """
        wanted: list[tuple[Point, object]] = []
        if kind == "pick":
            for obj in self.scenario.objects:
                if obj.id == target:
                    continue
                if obj.id not in self.deliver:  # already delivered: it stays at its goal
                    wanted.append((obj.goal, None))
                    continue
                if obj.id != self.holding:
                    wanted.append((obj.start, ObjectAt(obj.id, "start")))
                wanted.append((obj.goal, ObjectAt(obj.id, "goal")))
        elif kind == "push":
            pushable = set(self.pushes.pushable)
            for item in self.scenario.clutter:
                if item.id == target:
                    continue
                if item.id not in pushable:
                    wanted.append((push_contact(item.rect, push.direction), None))
                    continue
                for position, rect in self.pushes.positions(item.id).items():
                    wanted.append((push_contact(rect, push.direction), (item.id, position)))
        out = []
        for point, tag in wanted:
            condition = out_of_reach(self.grid, point, heading, posture, tag)
            if condition is not None:
                out.append(condition)
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
            confusions = blockers.confusions(kind, target, heading, posture, push)
            for piece, tags in split_box(box, conditions + confusions):
                forbidden = frozenset(t for t in tags if not isinstance(t, ObjectAt))
                confusers = frozenset(t for t in tags if isinstance(t, ObjectAt))
                out.append(PoseOption(kind, target, heading, posture.name, piece, hand, forbidden, push, confusers))
    return out


def _sign(value: int) -> int:
    return (value > 0) - (value < 0)
