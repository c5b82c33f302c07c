"""The plan validator: ``docs/plan-format.md`` "What makes a plan valid", checked without the solver.

:func:`validate_plan` lists every violation of a plan for a scenario, one message
each, naming the rule, the phase index and the ids involved, so that a person can
find the fault in the plan file. An empty list means the plan is valid.

What is checked (tolerance ``TOL`` = 1 mm unless said):

structure
    A plan with phases; phase 0 is ``start`` at ``robot.start`` with the robot's
    heading, an empty hand and the scenario's initial positions; targets, postures
    and ``holding`` name ids of the scenario; every object and clutter id is present
    in every phase.
rule 1 (area, clearance)
    The base disc lies inside the area at every phase; every segment between
    consecutive bases keeps at least ``robot.radius - 1e-6`` m from every table and
    obstacle.
rule 2 (holding)
    ``holding`` changes only at ``pick`` (null -> target) and ``place`` (target -> null).
rule 3 (objects stay)
    An object not held at the end of the previous phase is where it was.
rule 4 (reach, arm line, place)
    At a pick or place the target lies within the named posture's ranges, and the
    arm line (base centre to target, the paper's Eq. 19) crosses no obstacle or
    clutter. A placed object stands fully on a table, overlaps no other object or
    clutter and, as ``docs/design.md`` decides (a place delivers, the paper's
    Eq. 12), stands at its goal.
rule 5 (push)
    Clutter moves only in a push of it; the stroke is axis-aligned and moves the
    clutter by the base's displacement; the clutter ends fully on the same table and
    neither ends on nor sweeps through anything. ``docs/design.md`` adds the push's
    arm (with an empty hand or holding an object, which moves with the base): a heading
    along or across the stroke (never backwards), the
    push contact (``kinematics.push_contact``) within the posture's ranges from the
    base where the stroke starts, and a clear arm line to it.
rule 6 (goal)
    In the last phase every object is at its goal and nothing is held.
rule 7 (held object)
    A held object is where the hand is: within the ranges of the posture that picked
    it, at the robot-frame offset it was picked with, so it moves (and turns) with the
    base, a push stroke included.
rule 8 (objective)
    ``objective`` is finite and equals the task cost recomputed from the phases
    (:func:`task_cost`, within ``OBJECTIVE_RTOL``); it is null only when the status
    has no plan.
rule 9 (hand room)
    At a push the contact (where the hand meets the piece) lies within the posture's
    ranges from the base where the stroke starts, and the hand there, the cube the env
    uses (``kinematics.hand_blocker``), overlaps no other piece of clutter and no object
    but the one held.

The format's rules are physical (clearance, the exact arm line). The environment's
rules are the planner's model, a little stricter (``docs/design.md``, "The env's rules
are the planner's model"): :func:`env_refusals` lists, apart from the violations and
without making a plan invalid, the phases the env refuses under them (a move with no
common region of some octagon, an acting pose in a corner zone, an arm whose base and
hand share no side of an obstacle or clutter).

Units are metres.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from expert.plans import Phase, Plan, task_cost
from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import (
    Heading,
    Point,
    Rect,
    discs_overlap,
    heading_of,
    segment_rect_distance,
    to_world_frame,
)
from fetchcarry_env.kinematics import (
    arm_line_clear,
    hand_blocker,
    hand_offset,
    push_contact,
    push_headings,
    swept_rect,
)
from fetchcarry_env.observation import WorldState
from fetchcarry_env.rules import arm_refusal, move_refusal, pose_refusal
from fetchcarry_env.scenario import Clutter, Posture, Scenario

TOL = 1e-3  # metres: tolerance of positions, reach ranges and overlaps (docs/plan-format.md)
CLEARANCE_SLACK = 1e-6  # metres: a base segment may come this much closer than the radius (rule 1)
OBJECTIVE_RTOL = 1e-6  # relative tolerance of the objective against the task cost recomputed (rule 8)


@dataclass(frozen=True)
class _Context:
    """The scenario's lookup tables and the plan's phases, shared by the rule checks."""

    scenario: Scenario
    phases: tuple[Phase, ...]
    postures: dict[str, Posture]
    object_ids: frozenset[str]
    clutter: dict[str, Clutter]
    holding: str | None = None

    @classmethod
    def of(cls, scenario: Scenario, plan: Plan, holding: str | None = None) -> _Context:
        return cls(
            scenario=scenario,
            holding=holding,
            phases=plan.phases,
            postures={p.name: p for p in scenario.robot.postures},
            object_ids=frozenset(o.id for o in scenario.objects),
            clutter={c.id: c for c in scenario.clutter},
        )

    def steps(self) -> Iterator[tuple[int, Phase, Phase]]:
        """``(k, phase k-1, phase k)`` for every phase after the start."""
        for k in range(1, len(self.phases)):
            yield k, self.phases[k - 1], self.phases[k]

    def clutter_rect(self, clutter_id: str, phase: Phase) -> Rect | None:
        """The clutter's footprint centred where ``phase`` has it, or None if the phase lacks it."""
        center = phase.clutter.get(clutter_id)
        if center is None:
            return None
        width, depth = self.clutter[clutter_id].rect.size
        return Rect.around(center, width / 2, depth / 2)

    def clutter_rects(self, phase: Phase, *, excluding: str | None = None) -> dict[str, Rect]:
        """Every clutter footprint (by id) at ``phase``, but ``excluding``."""
        rects = {cid: self.clutter_rect(cid, phase) for cid in self.clutter if cid != excluding}
        return {cid: rect for cid, rect in rects.items() if rect is not None}


def validate_plan(scenario: Scenario, plan: Plan, *, holding: str | None = None) -> list[str]:
    """Every way ``plan`` breaks ``docs/plan-format.md`` for ``scenario``, one message each; empty when valid.

    ``holding`` names an object already in the hand at the start, as in plans made
    mid-episode with ``plan(..., holding=...)``; its ``start`` in the scenario is then
    not where it is.
    """
    if plan.status not in ("optimal", "feasible") or not plan.phases:
        return [
            f"structure: the plan has no phases to check (status {plan.status!r})",
            *_rule8_objective(scenario, plan),
        ]
    context = _Context.of(scenario, plan, holding)
    return [
        *_check_structure(context, plan),
        *_rule1_base(context),
        *_each_step(context, _rule2_holding),
        *_each_step(context, _rule3_objects_stay),
        *_each_step(context, _rule4_pick_place),
        *_each_step(context, _rule5_push),
        *_rule6_goal(context),
        *_rule7_held_object(context),
        *_rule8_objective(scenario, plan),
        *_each_step(context, _rule9_hand_room),
    ]


def env_refusals(
    scenario: Scenario, plan: Plan, *, holding: str | None = None, lattice: Lattice | None = None
) -> list[str]:
    """The phases of ``plan`` that the env refuses under its move, pose and arm rules, one message each.

    Not violations of the file format (a plan may be valid and still be listed here): the
    env's rules are the planner's model stated exactly, a little stricter than the
    format's physical ones, so a hand-written plan that clears a corner by less than the
    octagon's margin, or reaches past an obstacle's corner, is flagged with its phase.
    ``lattice`` is the env's action lattice; None tests every base in metres (never more
    lenient than the env's lattice test). Phases the format refuses for their structure
    (unknown ids, missing items) are skipped: the violations name them.
    """
    if plan.status not in ("optimal", "feasible") or not plan.phases:
        return []
    context = _Context.of(scenario, plan, holding)
    out = []
    for k, before, after in context.steps():
        reason = _env_refusal(context, lattice, before, after)
        if reason is not None:
            out.append(
                f"env rules: phase {k} {after.action} from {_pt(before.base)} to {_pt(after.base)}: "
                f"the env refuses it: {reason}"
            )
    return out


def _env_refusal(context: _Context, lattice: Lattice | None, before: Phase, after: Phase) -> str | None:
    """Why the env refuses the step from ``before`` to ``after`` (fetchcarry_env.rules), or None."""
    scenario = context.scenario
    if after.action == "push":
        return _env_push_refusal(context, lattice, before, after)
    refusal = move_refusal(scenario, lattice, before.base, after.base)
    if refusal is not None or after.action not in ("pick", "place") or after.target not in context.object_ids:
        return refusal
    hand = (before if after.action == "pick" else after).objects.get(after.target)
    if hand is None or set(after.clutter) != set(context.clutter):
        return None
    state = WorldState(after.base, after.heading, before.holding, {}, dict(after.clutter))
    bases = (after.base,)
    return pose_refusal(scenario, lattice, bases) or arm_refusal(scenario, state, lattice, bases, (hand[:2],))


def _env_push_refusal(context: _Context, lattice: Lattice | None, before: Phase, after: Phase) -> str | None:
    """Why the env refuses the push stroke from ``before`` to ``after``: its move, its poses, its arm; or None."""
    scenario = context.scenario
    refusal = move_refusal(scenario, lattice, before.base, after.base)
    start_rect = context.clutter_rect(after.target, before) if after.target in context.clutter else None
    direction = heading_of(_snap_small((after.base[0] - before.base[0], after.base[1] - before.base[1])))
    if refusal is not None or start_rect is None or direction is None or set(before.clutter) != set(context.clutter):
        return refusal
    bases = (before.base, after.base)
    stroke = (after.base[0] - before.base[0], after.base[1] - before.base[1])
    contact = push_contact(start_rect, direction)
    hands = (contact, (contact[0] + stroke[0], contact[1] + stroke[1]))
    state = WorldState(before.base, after.heading, before.holding, {}, dict(before.clutter))
    return pose_refusal(scenario, lattice, bases) or arm_refusal(
        scenario, state, lattice, bases, hands, ignore=after.target
    )


def _each_step(context: _Context, check: Callable[[_Context, int, Phase, Phase], list[str]]) -> list[str]:
    """The messages of ``check(context, k, phase k-1, phase k)`` for every phase after the start, in order."""
    return [message for k, before, after in context.steps() for message in check(context, k, before, after)]


# ---------------------------------------------------------------------- structure
def _check_structure(context: _Context, plan: Plan) -> list[str]:
    scenario = context.scenario
    out = []
    if plan.scenario != scenario.name:
        out.append(f"structure: the plan is for scenario {plan.scenario!r}, not {scenario.name!r}")
    out.extend(_check_start(context))
    for k, phase in enumerate(context.phases):
        out.extend(_check_ids(context, k, phase))
        if k >= 1:
            out.extend(_check_target_and_posture(context, k, phase))
    return out


def _check_start(context: _Context) -> list[str]:
    robot = context.scenario.robot
    start = context.phases[0]
    out = []
    if start.action != "start":
        out.append(f"structure: phase 0 must be 'start', not {start.action!r}")
    if not _same(start.base, robot.start):
        out.append(f"structure: phase 0 base {_pt(start.base)} is not robot.start {_pt(robot.start)}")
    if start.heading != robot.heading:
        out.append(f"structure: phase 0 heading {start.heading!r} is not the robot's heading {robot.heading!r}")
    if start.target is not None or start.posture is not None:
        out.append("structure: phase 0 must have no target or posture")
    if start.holding != context.holding:
        out.append(f"structure: phase 0 must hold {context.holding!r}, not {start.holding!r}")
    for obj in context.scenario.objects:
        at = start.objects.get(obj.id)
        if at is not None and obj.id != context.holding and not _same(at, obj.start):
            out.append(f"structure: phase 0 object {obj.id!r} is at {_pt(at)}, not its start {_pt(obj.start)}")
    for item in context.scenario.clutter:
        at = start.clutter.get(item.id)
        if at is not None and not _same(at, item.rect.center):
            out.append(f"structure: phase 0 clutter {item.id!r} is at {_pt(at)}, not its start {_pt(item.rect.center)}")
    return out


def _check_ids(context: _Context, k: int, phase: Phase) -> list[str]:
    out = []
    for kind, expected, present in (
        ("object", context.object_ids, set(phase.objects)),
        ("clutter", set(context.clutter), set(phase.clutter)),
    ):
        out.extend(f"structure: phase {k} lacks {kind} {i!r}" for i in sorted(expected - present))
        out.extend(f"structure: phase {k} names unknown {kind} {i!r}" for i in sorted(present - expected))
    if phase.holding is not None and phase.holding not in context.object_ids:
        out.append(f"structure: phase {k} holds {phase.holding!r}, which is not an object of the scenario")
    return out


def _check_target_and_posture(context: _Context, k: int, phase: Phase) -> list[str]:
    action = phase.action
    if action == "start":
        return [f"structure: phase {k} is a second 'start'"]
    if action == "move":
        if phase.target is not None or phase.posture is not None:
            return [f"structure: phase {k} move must have no target and no posture"]
        return []
    out = []
    kind, ids = ("clutter", set(context.clutter)) if action == "push" else ("object", context.object_ids)
    if phase.target not in ids:
        out.append(f"structure: phase {k} {action} target {phase.target!r} is not a {kind} id of the scenario")
    if phase.posture not in context.postures:
        out.append(f"structure: phase {k} {action} posture {phase.posture!r} is not a posture of the robot")
    return out


# ---------------------------------------------------------------------- rule 1
def _rule1_base(context: _Context) -> list[str]:
    scenario = context.scenario
    radius = scenario.robot.radius
    out = []
    for k, phase in enumerate(context.phases):
        if not scenario.area.contains_disc(phase.base, radius, tol=TOL):
            out.append(f"rule 1 (area): phase {k} base disc at {_pt(phase.base)} is not inside the area")
    blockers = [(f"table {t.id!r}", t.rect) for t in scenario.tables]
    blockers += [(f"obstacle {o.id!r}", o.rect) for o in scenario.obstacles]
    for k, before, after in context.steps():
        for name, rect in blockers:
            if _far_from_segment(before.base, after.base, rect, radius):
                continue
            distance = segment_rect_distance(before.base, after.base, rect)
            if distance < radius - CLEARANCE_SLACK:
                out.append(
                    f"rule 1 (clearance): phase {k} {after.action} from {_pt(before.base)} to {_pt(after.base)} "
                    f"passes {distance:.3f} m from {name}, less than the base radius {radius:.3f} m"
                )
    return out


def _far_from_segment(p: Point, q: Point, rect: Rect, radius: float) -> bool:
    """A cheap, exact-enough pre-test: True only when ``rect`` is surely more than ``radius`` from segment ``p``-``q``.

    Outside the segment's bounding box grown by ``radius``, or farther from the segment's
    line than ``radius`` plus the rectangle's half-diagonal. Keeps rule 1 fast for the
    1,024 obstacles a scenario may hold (metres).
    """
    if (
        rect.min_x > max(p[0], q[0]) + radius
        or rect.max_x < min(p[0], q[0]) - radius
        or rect.min_y > max(p[1], q[1]) + radius
        or rect.max_y < min(p[1], q[1]) - radius
    ):
        return True
    dx, dy = q[0] - p[0], q[1] - p[1]
    length = math.hypot(dx, dy)
    if not (0.0 < length < math.inf):
        return False
    cx, cy = rect.center
    from_line = abs((cx - p[0]) * dy - (cy - p[1]) * dx) / length
    half_diagonal = math.hypot(*rect.size) / 2
    return from_line > radius + half_diagonal + 1e-9


# ---------------------------------------------------------------------- rule 2
def _rule2_holding(context: _Context, k: int, before: Phase, after: Phase) -> list[str]:
    was, now, target = before.holding, after.holding, after.target
    out = []
    if after.action == "pick":
        if was is not None:
            out.append(f"rule 2 (holding): phase {k} pick {target!r} while already holding {was!r}")
        if now != target:
            out.append(f"rule 2 (holding): phase {k} pick {target!r} ends holding {now!r}, not {target!r}")
    elif after.action == "place":
        if was != target:
            out.append(f"rule 2 (holding): phase {k} place {target!r} while holding {was!r}, not {target!r}")
        if now is not None:
            out.append(f"rule 2 (holding): phase {k} place {target!r} ends holding {now!r}, not nothing")
    elif now != was:
        out.append(
            f"rule 2 (holding): phase {k} {after.action} changes holding from {was!r} to {now!r}; "
            "only a pick or a place may"
        )
    return out


# ---------------------------------------------------------------------- rule 3
def _rule3_objects_stay(context: _Context, k: int, before: Phase, after: Phase) -> list[str]:
    out = []
    for object_id in sorted(context.object_ids):
        if before.holding == object_id:
            continue  # carried, or placed (rule 4 checks where)
        was, now = before.objects.get(object_id), after.objects.get(object_id)
        if was is not None and now is not None and not _same(was, now):
            out.append(
                f"rule 3 (objects stay): phase {k} object {object_id!r} moves from {_pt(was)} to {_pt(now)} "
                "although it is not held"
            )
    return out


# ---------------------------------------------------------------------- rule 4
def _rule4_pick_place(context: _Context, k: int, before: Phase, after: Phase) -> list[str]:
    if after.action not in ("pick", "place") or after.target not in context.object_ids:
        return []
    posture = context.postures.get(after.posture or "")
    # A pick grasps the object where it stood; a place puts it where this phase has it.
    where = (before if after.action == "pick" else after).objects.get(after.target)
    if posture is None or where is None:
        return []
    what = f"phase {k} {after.action} {after.target!r}"
    out = _reach(f"rule 4 (reach): {what}", posture, after.base, after.heading, where)
    blockers = {f"obstacle {o.id!r}": o.rect for o in context.scenario.obstacles}
    blockers.update({f"clutter {cid!r}": rect for cid, rect in context.clutter_rects(after).items()})
    out.extend(_arm_line(f"rule 4 (arm line): {what}", after.base, where, blockers))
    if after.action == "place":
        out.extend(_placement(context, k, after, where))
    return out


def _placement(context: _Context, k: int, phase: Phase, where: Point) -> list[str]:
    scenario = context.scenario
    obj = scenario.object(phase.target)
    what = f"rule 4 (place): phase {k} place {obj.id!r} at {_pt(where)}"
    out = []
    if not any(t.rect.contains_disc(where, obj.radius, tol=TOL) for t in scenario.tables):
        out.append(f"{what} does not stand fully on a table")
    for other in scenario.objects:
        at = phase.objects.get(other.id)
        if other.id != obj.id and at is not None and discs_overlap(where, obj.radius, at, other.radius, tol=TOL):
            out.append(f"{what} overlaps object {other.id!r}")
    for cid, rect in context.clutter_rects(phase).items():
        if rect.overlaps_disc(where, obj.radius, tol=TOL):
            out.append(f"{what} overlaps clutter {cid!r}")
    if not _same(where, obj.goal):
        out.append(f"{what} is not at its goal {_pt(obj.goal)} (docs/design.md: a place delivers)")
    return out


# ---------------------------------------------------------------------- rule 5
def _rule5_push(context: _Context, k: int, before: Phase, after: Phase) -> list[str]:
    out = []
    for cid in context.clutter:
        was, now = before.clutter.get(cid), after.clutter.get(cid)
        pushed = after.action == "push" and after.target == cid
        if was is not None and now is not None and not pushed and not _same(was, now):
            out.append(
                f"rule 5 (push): phase {k} clutter {cid!r} moves from {_pt(was)} to {_pt(now)} outside a push of it"
            )
    if after.action == "push" and after.target in context.clutter:
        out.extend(_push(context, k, before, after))
    return out


def _push(context: _Context, k: int, before: Phase, after: Phase) -> list[str]:
    cid = after.target
    what = f"rule 5 (push): phase {k} push {cid!r}"
    start_rect, end_rect = context.clutter_rect(cid, before), context.clutter_rect(cid, after)
    if start_rect is None or end_rect is None:
        return []
    stroke = (after.base[0] - before.base[0], after.base[1] - before.base[1])
    direction = heading_of(_snap_small(stroke))
    if direction is None:
        return [f"{what}: the stroke {_pt(stroke)} is not axis-aligned (no diagonal or empty pushes)"]
    out = []
    moved = (end_rect.center[0] - start_rect.center[0], end_rect.center[1] - start_rect.center[1])
    if not _same(moved, stroke):
        out.append(f"{what}: the clutter moves by {_pt(moved)}, not by the base's stroke {_pt(stroke)}")
    out.extend(_push_end(context, what, cid, before, after, start_rect, end_rect, direction))
    out.extend(_push_arm(context, what, before, after, start_rect, direction))
    return out


def _push_end(
    context: _Context,
    what: str,
    cid: str,
    before: Phase,
    after: Phase,
    start_rect: Rect,
    end_rect: Rect,
    direction: Heading,
) -> list[str]:
    scenario = context.scenario
    out = []
    table = next((t for t in scenario.tables if t.rect.contains_rect(start_rect, tol=TOL)), None)
    if table is not None and not table.rect.contains_rect(end_rect, tol=TOL):
        out.append(f"{what}: the clutter ends at {_pt(end_rect.center)}, not fully on its table {table.id!r}")
    # Everything the clutter slides over on its way from where it stood to where it ends.
    swept = swept_rect(start_rect, direction, math.dist(start_rect.center, end_rect.center))
    for other, rect in context.clutter_rects(after, excluding=cid).items():
        if swept.overlaps_rect(rect, tol=TOL):
            out.append(f"{what}: the clutter runs into clutter {other!r}")
    for obj in scenario.objects:
        at = after.objects.get(obj.id)
        if at is not None and obj.id != before.holding and swept.overlaps_disc(at, obj.radius, tol=TOL):
            out.append(f"{what}: the clutter runs into object {obj.id!r}")
    for obstacle in scenario.obstacles:
        if swept.overlaps_rect(obstacle.rect, tol=TOL):
            out.append(f"{what}: the clutter runs into obstacle {obstacle.id!r}")
    return out


def _push_arm(
    context: _Context, what: str, before: Phase, after: Phase, start_rect: Rect, direction: Heading
) -> list[str]:
    out = []
    if after.heading not in push_headings(direction):
        out.append(f"{what}: heading {after.heading!r} pushes backwards along {direction!r} (docs/design.md)")
    posture = context.postures.get(after.posture or "")
    if posture is None:
        return out
    contact = push_contact(start_rect, direction)
    blockers = {f"obstacle {o.id!r}": o.rect for o in context.scenario.obstacles}
    blockers.update(
        {f"clutter {cid!r}": rect for cid, rect in context.clutter_rects(before, excluding=after.target).items()}
    )
    out.extend(_arm_line(f"{what}: arm line", before.base, contact, blockers))
    return out


# ---------------------------------------------------------------------- rule 6
def _rule6_goal(context: _Context) -> list[str]:
    last_index = len(context.phases) - 1
    last = context.phases[-1]
    out = []
    for obj in context.scenario.objects:
        at = last.objects.get(obj.id)
        if at is not None and not _same(at, obj.goal):
            out.append(
                f"rule 6 (goal): in the last phase ({last_index}) object {obj.id!r} is at {_pt(at)}, "
                f"{math.dist(at, obj.goal):.3f} m from its goal {_pt(obj.goal)}"
            )
    if last.holding is not None:
        out.append(f"rule 6 (goal): in the last phase ({last_index}) the robot still holds {last.holding!r}")
    return out


# ---------------------------------------------------------------------- rule 7
def _rule7_held_object(context: _Context) -> list[str]:
    out: list[str] = []
    grip: tuple[str, Posture | None, Point] | None = None  # (object, posture that picked it, robot-frame offset)
    first = context.phases[0]
    if first.holding in context.object_ids and first.holding in first.objects:
        # Held before the plan starts: no pick to name the posture; it must lie within one of them.
        offset = hand_offset(first.base, first.heading, first.objects[first.holding])
        if any(p.reaches(*offset, tol=TOL) for p in context.postures.values()):
            grip = (first.holding, None, offset)
        else:
            out.append(
                f"rule 7 (held object): phase 0 holding {first.holding!r}: it is at "
                f"{_pt(first.objects[first.holding])}, {_pt(offset)} ahead/left of the base, within no posture's ranges"
            )
    for k, _before, after in context.steps():
        if after.action == "pick" and after.holding == after.target and after.target in after.objects:
            posture = context.postures.get(after.posture or "")
            offset = hand_offset(after.base, after.heading, after.objects[after.target])
            # A grasp out of reach is rule 4's fault; the phases that carry it are not checked against it again.
            grip = (after.target, posture, offset) if posture and posture.reaches(*offset, tol=TOL) else None
            continue
        held = after.holding
        if held is None or grip is None or grip[0] != held or held not in after.objects:
            continue  # nothing held, or a grasp rule 2 or 4 already refuses
        _, posture, offset = grip
        at = after.objects[held]
        what = f"rule 7 (held object): phase {k} {after.action} holding {held!r}"
        if posture is not None:
            out.extend(_reach(f"{what}: it", posture, after.base, after.heading, at))
        dx, dy = to_world_frame(after.heading, *offset)
        hand = (after.base[0] + dx, after.base[1] + dy)
        if not _same(at, hand):
            out.append(
                f"{what}: it is at {_pt(at)}, not in the hand at {_pt(hand)} (it moves with the base, "
                f"at the offset {_pt(offset)} ahead/left it was picked with)"
            )
    return out


# ---------------------------------------------------------------------- rule 8
def _rule8_objective(scenario: Scenario, plan: Plan) -> list[str]:
    has_plan = plan.status in ("optimal", "feasible")
    what = f"rule 8 (objective): status {plan.status!r}"
    objective = plan.objective
    if not has_plan:
        return [] if objective is None else [f"{what} has no plan, so the objective must be null, not {objective!r}"]
    if not plan.phases:
        return []
    expected = task_cost(scenario, plan.phases)
    if objective is None:
        return [f"{what} has a plan, so the objective must be the task cost of its phases ({expected:.6g}), not null"]
    if not math.isfinite(objective):
        return [f"{what}: the objective {objective!r} is not a finite number (the phases' task cost is {expected:.6g})"]
    if not math.isclose(objective, expected, rel_tol=OBJECTIVE_RTOL, abs_tol=1e-9):
        return [f"{what}: the objective {objective:.6g} is not the phases' task cost recomputed, {expected:.6g}"]
    return []


# ---------------------------------------------------------------------- rule 9
def _rule9_hand_room(context: _Context, k: int, before: Phase, after: Phase) -> list[str]:
    if after.action != "push" or after.target not in context.clutter:
        return []
    start_rect = context.clutter_rect(after.target, before)
    end_rect = context.clutter_rect(after.target, after)
    direction = heading_of(_snap_small((after.base[0] - before.base[0], after.base[1] - before.base[1])))
    if start_rect is None or end_rect is None or direction is None:
        return []  # rule 5 names these
    what = f"rule 9 (hand room): phase {k} push {after.target!r}"
    contact = push_contact(start_rect, direction)
    posture = context.postures.get(after.posture or "")
    out = [] if posture is None else _reach(f"{what}: the push contact", posture, before.base, after.heading, contact)
    # The rule the env applies (rules._check_push): everything else where it stands when the stroke starts.
    others = context.clutter_rects(before, excluding=after.target)
    objects = [
        (obj.id, before.objects[obj.id], obj.radius)
        for obj in context.scenario.objects
        if obj.id in before.objects and obj.id != before.holding
    ]
    blocker = hand_blocker(contact, others.items(), objects)
    if blocker is not None:
        kind = "clutter" if blocker in others else "object"
        out.append(f"{what}: no room for the hand at the push contact {_pt(contact)}: {kind} {blocker!r} is there")
    return out


# ---------------------------------------------------------------------- shared checks
def _reach(prefix: str, posture: Posture, base: Point, heading: str, point: Point) -> list[str]:
    """Messages for each robot-frame axis on which ``point`` lies outside ``posture``'s ranges."""
    forward, lateral = hand_offset(base, heading, point)
    if posture.reaches(forward, lateral, tol=TOL):
        return []
    out = []
    low, high = posture.forward
    if not low - TOL <= forward <= high + TOL:
        out.append(
            f"{prefix} is {forward:.3f} m ahead, outside posture {posture.name!r} forward range [{low:.3f}, {high:.3f}]"
        )
    low, high = posture.lateral
    if not low - TOL <= lateral <= high + TOL:
        side = "to the left" if lateral > 0 else "to the right"
        out.append(
            f"{prefix} is {abs(lateral):.3f} m {side} (lateral {lateral:.3f}), outside posture {posture.name!r} "
            f"lateral range [{low:.3f}, {high:.3f}]"
        )
    return out


def _arm_line(prefix: str, base: Point, hand: Point, blockers: dict[str, Rect]) -> list[str]:
    """Messages for each blocker the straight arm line from ``base`` to ``hand`` crosses (Eq. 19)."""
    return [
        f"{prefix}: the arm line from {_pt(base)} to {_pt(hand)} crosses {name}"
        for name, rect in blockers.items()
        if not arm_line_clear(base, hand, [rect])
    ]


def _same(a: Point, b: Point) -> bool:
    """Equal within ``TOL`` on both coordinates."""
    return abs(a[0] - b[0]) <= TOL and abs(a[1] - b[1]) <= TOL


def _snap_small(vector: Point) -> Point:
    """``vector`` with components within ``TOL`` of zero set to zero (so near-axis strokes count as axis-aligned)."""
    return (0.0 if abs(vector[0]) <= TOL else vector[0], 0.0 if abs(vector[1]) <= TOL else vector[1])


def _pt(p: Point) -> str:
    return f"[{p[0]:.3f}, {p[1]:.3f}]"
