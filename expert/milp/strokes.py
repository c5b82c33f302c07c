"""Push-aside preprocessing (the paper's IV-E before the solve): strokes B and the s, o, q flags.

Generalised to any number of clutter items on any goal and every axis direction. For
each piece of clutter ``c`` that covers a goal (the paper's ``u_i = 1``) and each
direction ``d``:

- the stroke ``B`` is :func:`fetchcarry_env.kinematics.push_stroke`: the smallest whole
  multiple of the lattice resolution that leaves 1 cm between the piece and every goal
  disc it covered (the paper's constant B, per piece and direction);
- the direction is *blocked* (the paper's ``o_{i,n} = 1``) when the floor the piece
  sweeps (:func:`fetchcarry_env.kinematics.swept_rect`) leaves its table, or meets an
  obstacle, a piece of clutter that is never pushed, an object's start or any goal.
  The paper's ``s_{i,n}`` (a neighbour in region ``R_n`` of the piece) is the geometric
  test behind it; we test the swept floor directly, which covers Fig. 3(c);
- a neighbour that will itself be pushed does not block: the direction then waits for
  that neighbour to go first (a *precedence*), and two strokes whose floors meet at
  their ends are mutually exclusive.
- the direction is also blocked when the hand (a cube of ``2 * HAND_HALF_SIZE`` at the
  push contact) has no room behind the piece: an object at its start or a piece of
  clutter that is never pushed stands there (the environment refuses such a push); a
  pushable neighbour there makes the push wait for it, as on the swept floor; the goal
  of another object there makes the push come before that object's place
  (``PushCandidate.hand_goals``).

Which pushes the arm can do from where (forward or lateral, the paper's ``q`` of
Fig. 3(d): the arm sweeping across a neighbour) is decided per pose option in
:mod:`expert.milp.options`. The stroke constraints (Eq. 20-26) are in
:mod:`expert.milp.push`. Nothing here depends on the number of phases or on the solver.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from expert.milp.grid import Grid
from fetchcarry_env.geometry import HEADINGS, Heading, Point, Rect, heading_vector
from fetchcarry_env.kinematics import HAND_HALF_SIZE, push_contact, push_stroke, swept_rect
from fetchcarry_env.scenario import Scenario


@dataclass(frozen=True)
class PushCandidate:
    """One direction in which one piece of clutter can be pushed off the goals it covers."""

    clutter: str
    direction: Heading
    stroke: float  # metres, the paper's B for this piece and direction
    cells: tuple[int, int]  # the stroke in lattice cells (di, dj)
    start: Rect  # the piece where it stands
    end: Rect  # the piece after the stroke
    swept: Rect  # the floor it slides over
    contact: Point  # where the hand's centre goes (kinematics.push_contact)
    hand_goals: tuple[str, ...] = ()  # objects whose goal leaves no room for the hand: push before they are placed

    @property
    def key(self) -> tuple[str, str]:
        return (self.clutter, self.direction)


@dataclass(frozen=True)
class PushPlan:
    """The preprocessing's answer: what must be pushed, how it can be, and the rules between pushes."""

    pushable: tuple[str, ...]  # clutter covering some goal: each is pushed exactly once
    candidates: tuple[PushCandidate, ...]
    blocked: dict[tuple[str, str], str] = field(default_factory=dict)  # (clutter, direction) -> why (o = 1)
    exclusive: tuple[tuple[int, int], ...] = ()  # candidate pairs that cannot both be used
    precedence: tuple[tuple[int, str], ...] = ()  # (candidate, clutter id): that clutter must be pushed first

    def positions(self, clutter_id: str) -> dict[str, Rect]:
        """Every place ``clutter_id`` can stand: ``"start"`` and each candidate direction."""
        out = {}
        for candidate in self.candidates:
            if candidate.clutter == clutter_id:
                out.setdefault("start", candidate.start)
                out[candidate.direction] = candidate.end
        return out


def plan_pushes(scenario: Scenario, grid: Grid, covers: dict[str, tuple[str, ...]], holding: str | None) -> PushPlan:
    """The push preprocessing (the paper's s, o, q generalised); see the module docstring."""
    pushable = tuple(sorted({c for ids in covers.values() for c in ids}))
    if not pushable:
        return PushPlan((), ())
    objects = {o.id: o for o in scenario.objects}
    discs = [(f"start of {o.id!r}", o.start, o.radius) for o in scenario.objects if o.id != holding]
    discs += [(f"goal of {o.id!r}", o.goal, o.radius) for o in scenario.objects]
    static_clutter = [c for c in scenario.clutter if c.id not in pushable]
    candidates: list[PushCandidate] = []
    blocked: dict[tuple[str, str], str] = {}
    waits: list[tuple[int, str]] = []
    for clutter_id in pushable:
        item = scenario.clutter_item(clutter_id)
        covered = [(objects[o].goal, objects[o].radius) for o, ids in covers.items() if clutter_id in ids]
        table = scenario.table_under_rect(item.rect)
        for direction in HEADINGS:
            stroke = push_stroke(item.rect, direction, covered, grid.resolution)
            ux, uy = heading_vector(direction)
            end = item.rect.translate(ux * stroke, uy * stroke)
            swept = swept_rect(item.rect, direction, stroke)
            reason = _blocked_by(swept, end, item.rect, table.rect if table else None, scenario, static_clutter, discs)
            hand = _hand_box(item.rect, direction)
            reason = reason or _no_hand_room(hand, scenario, static_clutter, holding)
            if reason is not None:
                blocked[(clutter_id, direction)] = reason
                continue
            cells = round(stroke / grid.resolution)
            candidate = PushCandidate(
                clutter=clutter_id,
                direction=direction,
                stroke=stroke,
                cells=(ux * cells, uy * cells),
                start=item.rect,
                end=end,
                swept=swept,
                contact=push_contact(item.rect, direction),
                hand_goals=tuple(o.id for o in scenario.objects if hand.overlaps_disc(o.goal, o.radius, tol=0.0)),
            )
            for other in pushable:
                other_rect = scenario.clutter_item(other).rect
                if other != clutter_id and (swept.overlaps_rect(other_rect) or hand.overlaps_rect(other_rect, tol=0.0)):
                    waits.append((len(candidates), other))
            candidates.append(candidate)
    return PushPlan(pushable, tuple(candidates), blocked, _exclusive_pairs(candidates), tuple(waits))


def _exclusive_pairs(candidates: list[PushCandidate]) -> tuple[tuple[int, int], ...]:
    """Pairs ``(a, b)``, ``a < b``, of strokes of different clutter where one sweeps over where the other ends."""
    return tuple(
        (a, b)
        for a in range(len(candidates))
        for b in range(a + 1, len(candidates))
        if candidates[a].clutter != candidates[b].clutter
        and (
            candidates[a].swept.overlaps_rect(candidates[b].end) or candidates[b].swept.overlaps_rect(candidates[a].end)
        )
    )


def _blocked_by(
    swept: Rect,
    end: Rect,
    start: Rect,
    table: Rect | None,
    scenario: Scenario,
    static_clutter: list,
    discs: list[tuple[str, Point, float]],
) -> str | None:
    """Why a stroke is impossible (the paper's o = 1), or None."""
    if table is None or not table.contains_rect(swept, tol=1e-9):
        return "the piece would leave its table"
    for obstacle in scenario.obstacles:
        if swept.overlaps_rect(obstacle.rect):
            return f"the piece would run into obstacle {obstacle.id!r}"
    for other in static_clutter:
        if swept.overlaps_rect(other.rect):
            return f"the piece would run into clutter {other.id!r}"
    for name, center, radius in discs:
        if end.overlaps_disc(center, radius) or (
            swept.overlaps_disc(center, radius) and not start.overlaps_disc(center, radius)
        ):
            return f"the piece would run into the {name}"
    return None


def _hand_box(rect: Rect, direction: Heading) -> Rect:
    """The hand (a cube of ``2 * HAND_HALF_SIZE``) at the contact for pushing ``rect`` along ``direction``."""
    return Rect.around(push_contact(rect, direction), HAND_HALF_SIZE, HAND_HALF_SIZE)


def _no_hand_room(hand: Rect, scenario: Scenario, static_clutter: list, holding: str | None) -> str | None:
    """Why the hand cannot stand behind the piece to push it, or None.

    The environment refuses a push whose hand would overlap another piece of clutter or
    an object (``fetchcarry_env.rules``); clutter that is never pushed and objects at
    their starts block the direction, a pushable neighbour there makes the push wait
    for it (a precedence, like a neighbour on the swept floor).
    """
    for other in static_clutter:
        if other.rect.overlaps_rect(hand, tol=0.0):
            return f"no room for the hand behind the piece: clutter {other.id!r} is there"
    for obj in scenario.objects:
        if obj.id != holding and hand.overlaps_disc(obj.start, obj.radius, tol=0.0):
            return f"no room for the hand behind the piece: object {obj.id!r} is there"
    return None
