"""Heading x posture selection at picks, places and pushes (the paper's Eq. 14-17) and the pose options.

The paper selects, per phase, one of ``4 x N_pos`` heading-posture pairs
(``theta_k^{fore|back|left|right, alpha}``, Eq. 14-15), exactly at picks and places
(Eq. 16-17), and ties the end effector to the base through it. We enumerate these
choices per action before the solve as *pose options*
(:class:`expert.milp.problem.PoseOption`): for an action (pick object i, place
object i, push piece c in direction d), a heading h and a posture alpha, the hand's
point is known (the object's start, its goal, the push contact), so the posture's
ranges turn into a box of lattice points for the base. One binary ``z_{o,k}`` per
option and phase is the product ``theta_k^{h,alpha} * theta_{i,k}^{pck|plc}`` of the
paper, disaggregated (tighter than linearising the product):

- Eq. 14, 16: at most one option per phase (:func:`add_posture_constraints`,
  together with one action per phase in :mod:`expert.milp.actions`);
- Eq. 15, 17: ``theta_k^{h,alpha} = sum`` of the options with that heading and posture,
  and ``theta_{i,k}^{pck} = sum`` of the pick options of ``i`` (expressions, no variables);
- the reach constraint: the acting base lies in the chosen option's box, written as
  one aggregated big-M per bound and phase (valid because at most one option is on).

The box is also cut (:func:`expert.milp.grid.split_box`) by the static parts of the
collision rules: the base disc off every table and obstacle, and the arm line (Eq. 19)
clear of every obstacle and of clutter that never moves. Pushable clutter moves, so
options whose arm line it would block in some position carry that position as a
*forbidden state* (constraints in :mod:`expert.milp.collision`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pyscipopt import quicksum

from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import Condition, Grid, HalfPlane, IndexBox, base_regions, split_box
from expert.milp.problem import PoseOption
from expert.milp.push import PushCandidate, PushPlan
from fetchcarry_env.geometry import HEADINGS, Heading, Point, Rect, to_world_frame
from fetchcarry_env.kinematics import push_headings
from fetchcarry_env.scenario import Posture, Scenario

if TYPE_CHECKING:
    from expert.milp.variables import Milp

HAND_TOL = 5e-7  # metres: a hand point this close to a region counts as inside (float32 observations)


def reach_box(grid: Grid, hand: Point, heading: Heading, posture: Posture) -> IndexBox:
    """Lattice points from which ``posture`` at ``heading`` puts the hand on ``hand``."""
    offsets = [to_world_frame(heading, f, lat) for f in posture.forward for lat in posture.lateral]
    dxs, dys = [o[0] for o in offsets], [o[1] for o in offsets]
    return grid.box_between((hand[0] - max(dxs), hand[1] - max(dys)), (hand[0] - min(dxs), hand[1] - min(dys)))


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

    def __init__(self, scenario: Scenario, grid: Grid, pushes: PushPlan) -> None:
        radius = scenario.robot.radius
        self.grid = grid
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


def pose_options(
    scenario: Scenario,
    grid: Grid,
    deliver: tuple[str, ...],
    holding: str | None,
    pushes: PushPlan,
    deadline: Deadline = NEVER,
) -> list[PoseOption]:
    """Every pick, place and push pose option of the problem (see the module docstring); checks ``deadline``."""
    blockers = _Blockers(scenario, grid, pushes)
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
            for piece, forbidden in split_box(box, conditions):
                out.append(PoseOption(kind, target, heading, posture.name, piece, hand, forbidden, push))
    return out


def _sign(value: int) -> int:
    return (value > 0) - (value < 0)


# ---------------------------------------------------------------------- constraints
def add_posture_constraints(milp: Milp) -> None:
    """Eq. 14-17 and the reach boxes: the acting base lies in the box of the option chosen."""
    problem, model, grid = milp.problem, milp.model, milp.problem.grid
    for k in range(1, milp.n_phases):
        # Picks and places act from base_k; pushes from base_{k-1} (the stroke's start).
        for acting, group in ((k, milp.arm_options_at(k)), (k - 1, milp.push_options_at(k))):
            if not group or acting == 0:
                continue
            for axis, coords in ((0, milp.u), (1, milp.v)):
                var_lo, var_hi = grid.var_bounds(axis)
                lower = quicksum((grid.lower(problem.options[o].box.lo(axis)) - var_lo) * z for o, z in group)
                upper = quicksum((var_hi - grid.upper(problem.options[o].box.hi(axis))) * z for o, z in group)
                model.addCons(coords[acting] >= var_lo + lower, name=f"reach_lo_{axis}_{k}_{acting}")
                model.addCons(coords[acting] <= var_hi - upper, name=f"reach_hi_{axis}_{k}_{acting}")
