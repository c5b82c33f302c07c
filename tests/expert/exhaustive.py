"""An exhaustive optimal planner over the env's own rules, written apart from the MILP (tests only).

The **action model** is the paper's: the base moves to any lattice point; the arm picks
an object (not held) or places the held one at its goal, from any lattice pose, with
any heading and posture; a push moves only a piece of clutter that covers a goal, only
by the minimal stroke (:func:`fetchcarry_env.kinematics.push_stroke`), only along a
direction whose swept floor stays on its table and meets no obstacle, other clutter
where it stands, object start or goal (``expert/milp/strokes.py``'s restriction, the
paper's s/o/q), from where the base stands. Objects are at their start, in the hand or
at their goal; clutter where it stood or pushed by its stroke (no physics: no jam).

**Everything geometric is the env's rule**, not the planner's model: every pick, place
and push is asked of :func:`fetchcarry_env.rules.check_action` (from a base standing at
the pose: reach, the item the env would take, the pose rule, the arm rule; a push's
stroke with its move rule), and every move of the base of the env's move rule
(:func:`fetchcarry_env.rules.move_refusal`), vectorised from one base to every lattice
point with the same exact region bits (:mod:`fetchcarry_env.regions`); the optimal plan
found is replayed through ``check_action`` and ``move_refusal`` themselves.

**The search** is uniform-cost (Dijkstra) over states ``(base, configuration)``: the
base is the start or a lattice point where it may stand, the configuration what the hand
holds, where each object is and where each pushable piece is. A step costs the
project's task cost, ``travel + W1 * (objects not at their goals after the step)``
(``travel`` the paper's travel cost of the base's motion, ``W1 = DELIVERY_BONUS``): the
negative of the env's return, penalties aside. The first terminal state settled (every
object at its goal, the hand empty) is optimal.

Units: metres; lattice points are numbered in the order of :attr:`Exhaustive.cells`.
Only for small scenarios on coarse lattices.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np

from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.geometry import HEADINGS, Point, Rect, heading_vector
from fetchcarry_env.kinematics import (
    DELIVERY_BONUS,
    DIAGONAL_WEIGHT,
    HAND_HALF_SIZE,
    push_contact,
    push_headings,
    push_stroke,
    swept_rect,
    travel_cost,
)
from fetchcarry_env.observation import WorldState
from fetchcarry_env.regions import area_domain, grid_bits, octagon_bits, octagon_rows
from fetchcarry_env.rules import ResolvedPhase, check_action, in_area, move_blockers, move_refusal
from fetchcarry_env.scenario import Scenario

W1 = DELIVERY_BONUS  # the task's cost of each step an object is not at its goal
START, HAND, GOAL = 0, 1, 2  # where an object is
REACH = 0.75  # metres: lattice poses this close to a target are tried (beyond every default posture's reach)
GOAL_TOL = 1e-3  # metres: an object this close to its goal, and not held, is delivered (a plan's phases)


@dataclass(frozen=True)
class Config:
    """What the hand holds (object index, -1: nothing), where each object is, where each pushable piece is.

    ``pushed[c]`` is -1 while pushable piece ``c`` stands where it started, else the
    index (in ``HEADINGS``) of the direction it was pushed along.
    """

    holding: int
    places: tuple[int, ...]
    pushed: tuple[int, ...]

    @property
    def waiting(self) -> int:
        """Objects not at their goals."""
        return sum(place != GOAL for place in self.places)

    @property
    def done(self) -> bool:
        return self.waiting == 0 and self.holding == -1


@dataclass(frozen=True)
class Step:
    """One step of an optimal plan: the arm's action (``move``, ``pick``, ``place``, ``push``), where the base ends."""

    kind: str
    base: Point
    cost: float  # the step's task cost


@dataclass(frozen=True)
class Optimum:
    """The least task cost of any plan and one plan that has it; ``expanded``: states settled by the search."""

    cost: float
    steps: tuple[Step, ...]
    expanded: int

    @property
    def phases(self) -> int:
        """Phases of the plan, the start included (as a plan file counts them)."""
        return len(self.steps) + 1


@dataclass(frozen=True)
class _Act:
    """An arm action allowed from a lattice pose: the pose, where the base ends, its kind, the configuration after."""

    pose: int
    end: int
    kind: str
    after: Config


class _Table:
    """One configuration's bases: the least cost found, settled or not, and how each was reached."""

    def __init__(self, size: int) -> None:
        self.dist = np.full(size, math.inf)
        self.settled = np.zeros(size, dtype=bool)
        self.came = np.full(size, None, dtype=object)  # (configuration, base, kind, step cost) before each base

    def open_min(self) -> tuple[float, int]:
        """The least cost of a base not settled yet, and that base."""
        open_dist = np.where(self.settled, math.inf, self.dist)
        n = int(np.argmin(open_dist))
        return float(open_dist[n]), n

    def improve(self, bases: np.ndarray, values: np.ndarray, config: Config, n: int, kind: str, steps) -> None:
        """Lower ``bases`` to ``values``, reached from ``(config, n)`` by a step of ``kind`` costing ``steps``."""
        self.dist[bases] = values
        for base, step in zip(bases.tolist(), np.broadcast_to(steps, bases.shape).tolist(), strict=True):
            self.came[base] = (config, n, kind, step)


class Exhaustive:
    """The search for one scenario on one lattice (see the module docstring)."""

    def __init__(self, scenario: Scenario, lattice: Lattice) -> None:
        self.scenario, self.lattice = scenario, lattice
        radius = scenario.robot.radius
        walls = [rect for _, rect in move_blockers(scenario)]
        rows = np.array([octagon_rows(lattice, r, radius) for r in walls], dtype=np.int64).reshape(len(walls), -1, 3)
        bits = grid_bits(rows, lattice.shape)
        domain = area_domain(lattice, scenario.area, radius)
        ii, jj = np.meshgrid(np.arange(lattice.shape[0]), np.arange(lattice.shape[1]), indexing="ij")
        inside = (ii >= domain.i_lo) & (ii <= domain.i_hi) & (jj >= domain.j_lo) & (jj <= domain.j_hi)
        standing = inside & (bits != 0).all(axis=2)  # no move ends anywhere else (the move rule)
        self.cells = np.argwhere(standing)  # (N, 2) lattice indices of the bases
        self.number = {(int(i), int(j)): n for n, (i, j) in enumerate(self.cells.tolist())}
        self.bits = bits[self.cells[:, 0], self.cells[:, 1]]  # (N, walls): octagon regions holding each base
        self.x = lattice.origin[0] + self.cells[:, 0] * lattice.resolution  # Lattice.point's arithmetic
        self.y = lattice.origin[1] + self.cells[:, 1] * lattice.resolution
        start = scenario.robot.start
        self.start_bits = np.array([octagon_bits(lattice, r, radius, start) for r in walls], dtype=np.uint8)
        self.start_inside = in_area(scenario, lattice, start)
        self.pushable = [c.id for c in scenario.clutter if any(_covers(c.rect, o) for o in scenario.objects)]
        self._acts: dict[Config, list[_Act]] = {}
        if self.pushable and _near_a_line(lattice, start):
            raise NotImplementedError(
                "a push from the start could be allowed (it lies on a lattice line): not searched"
            )

    # ------------------------------------------------------------------ geometry
    def point(self, n: int) -> Point:
        """The base of state number ``n`` (``len(cells)``: the start), metres."""
        if n == len(self.cells):
            return self.scenario.robot.start
        return (float(self.x[n]), float(self.y[n]))

    def reachable(self, n: int) -> np.ndarray:
        """``(N,)`` bool: the lattice bases the move rule lets the base reach from base ``n`` in one move."""
        if n == len(self.cells):
            if not self.start_inside:
                return np.zeros(len(self.cells), dtype=bool)
            return ((self.bits & self.start_bits) != 0).all(axis=1)
        return ((self.bits & self.bits[n]) != 0).all(axis=1)

    def travel(self, n: int) -> np.ndarray:
        """``(N,)``: the travel cost from base ``n`` to every lattice base (``kinematics.travel_cost``), metres."""
        bx, by = self.point(n)
        dx, dy = np.abs(self.x - bx), np.abs(self.y - by)
        return dx + dy + DIAGONAL_WEIGHT * np.abs(dx - dy)

    # ------------------------------------------------------------------ the env's arm actions
    def world(self, config: Config, base: Point) -> WorldState:
        """The env's state of ``config`` with the base at ``base`` (heading irrelevant to the rules)."""
        objects = {}
        for obj, place in zip(self.scenario.objects, config.places, strict=True):
            at = obj.goal if place == GOAL else obj.start  # a held object's position matters to no rule
            objects[obj.id] = (at[0], at[1], 0.0)
        clutter = {c.id: c.rect.center for c in self.scenario.clutter}
        for c, direction in zip(self.pushable, config.pushed, strict=True):
            if direction >= 0:
                clutter[c] = _pushed_rect(self.scenario, self.lattice, c, HEADINGS[direction]).center
        holding = None if config.holding < 0 else self.scenario.objects[config.holding].id
        return WorldState(base, "+x", holding, objects, clutter)

    def acts(self, config: Config) -> list[_Act]:
        """Every pick, place and push the env accepts in ``config`` from a lattice pose (cached per configuration)."""
        if config not in self._acts:
            self._acts[config] = self._picks_and_places(config) + self._pushes(config)
        return self._acts[config]

    def _picks_and_places(self, config: Config) -> list[_Act]:
        out = []
        for o, obj in enumerate(self.scenario.objects):
            if config.holding < 0 and config.places[o] != HAND:
                target, mode = (obj.goal if config.places[o] == GOAL else obj.start), Mode.PICK
                after = replace(config, holding=o, places=_with(config.places, o, HAND))
            elif config.holding == o:
                target, mode = obj.goal, Mode.PLACE
                after = replace(config, holding=-1, places=_with(config.places, o, GOAL))
            else:
                continue
            for n in self._near(target):
                if any(self._accepts(config, n, self.cells[n], h, mode, obj.id) for h in HEADINGS):
                    out.append(_Act(n, n, mode.name.lower(), after))
        return out

    def _pushes(self, config: Config) -> list[_Act]:
        out = []
        for c, clutter_id in enumerate(self.pushable):
            if config.pushed[c] >= 0:
                continue
            for d, direction in enumerate(HEADINGS):
                stroke = self._stroke(config, clutter_id, direction)
                if stroke is None:
                    continue
                ux, uy = heading_vector(direction)
                rect = self.scenario.clutter_item(clutter_id).rect
                for n in self._near(push_contact(rect, direction)):
                    end = (int(self.cells[n][0]) + ux * stroke, int(self.cells[n][1]) + uy * stroke)
                    if any(self._accepts(config, n, end, h, Mode.PUSH, clutter_id) for h in push_headings(direction)):
                        after = replace(config, pushed=_with(config.pushed, c, d))
                        out.append(_Act(n, self.number[end], "push", after))
        return out

    def _accepts(self, config: Config, n: int, cell, heading: str, mode: Mode, target: str) -> bool:
        """Whether ``check_action`` accepts the action on ``target`` from a base standing at lattice base ``n``."""
        world, cell = self.world(config, self.point(n)), (int(cell[0]), int(cell[1]))
        for posture in range(len(self.scenario.robot.postures)):
            phase = check_action(self.scenario, world, self.lattice, Action(cell, heading, posture, mode))
            if isinstance(phase, ResolvedPhase) and phase.target == target:
                if mode == Mode.PUSH and cell not in self.number:
                    raise AssertionError(f"the env accepts a push ending off the bases: {cell}")
                return True
        return False

    def _near(self, point: Point) -> np.ndarray:
        """The lattice bases within ``REACH`` of ``point``."""
        return np.flatnonzero(np.hypot(self.x - point[0], self.y - point[1]) <= REACH)

    def _stroke(self, config: Config, clutter_id: str, direction: str) -> int | None:
        """The minimal stroke (cells) of ``clutter_id`` along ``direction`` if the paper allows it here, else None."""
        scenario, res = self.scenario, self.lattice.resolution
        rect = scenario.clutter_item(clutter_id).rect
        covered = [(o.goal, o.radius) for o in scenario.objects if _covers(rect, o)]
        stroke = push_stroke(rect, direction, covered, res)
        swept = swept_rect(rect, direction, stroke)
        ux, uy = heading_vector(direction)
        end = rect.translate(ux * stroke, uy * stroke)
        table = scenario.table_under_rect(rect)
        if table is None or not table.rect.contains_rect(swept, tol=1e-9):
            return None
        world = self.world(config, scenario.robot.start)
        others = [Rect.around(world.clutter[c.id], *(s / 2 for s in c.rect.size)) for c in scenario.clutter]
        others = [r for c, r in zip(scenario.clutter, others, strict=True) if c.id != clutter_id]
        if any(swept.overlaps_rect(r) for r in [*(o.rect for o in scenario.obstacles), *others]):
            return None
        holding = None if config.holding < 0 else scenario.objects[config.holding].id
        discs = [(o.start, o.radius) for o in scenario.objects if o.id != holding] + [
            (o.goal, o.radius) for o in scenario.objects
        ]
        if any(
            end.overlaps_disc(c, r) or (swept.overlaps_disc(c, r) and not rect.overlaps_disc(c, r)) for c, r in discs
        ):
            return None  # it would run into an object's start or a goal (strokes._blocked_by)
        hand = Rect.around(push_contact(rect, direction), HAND_HALF_SIZE, HAND_HALF_SIZE)
        if any(hand.overlaps_rect(r, tol=0.0) for r in others):
            return None
        return round(stroke / res)

    # ------------------------------------------------------------------ the search
    def solve(self, max_expanded: int = 2_000_000) -> Optimum | None:
        """The least task cost of delivering every object (None: no plan); uniform-cost search."""
        first = Config(-1, tuple(START for _ in self.scenario.objects), tuple(-1 for _ in self.pushable))
        tables = {first: _Table(len(self.cells) + 1)}
        tables[first].dist[-1] = 0.0  # the start is the last base
        for expanded in range(1, max_expanded + 1):
            config, n = min(((c, t.open_min()) for c, t in tables.items()), key=lambda ct: ct[1][0])
            value, n = n
            if not math.isfinite(value):
                return None
            tables[config].settled[n] = True
            if config.done:
                return Optimum(value, self._path(tables, config, n), expanded)
            self._relax(tables, config, n, value)
        raise RuntimeError(f"the search settled {max_expanded} states without finishing")

    def _relax(self, tables: dict[Config, _Table], config: Config, n: int, value: float) -> None:
        """Every step from state ``(config, n)`` at cost ``value``: moves, then the arm's actions."""
        waiting = W1 * config.waiting
        travel = self.travel(n)
        ok = self.reachable(n)
        if n < len(self.cells):
            ok[n] = False  # a move that goes nowhere
        table = tables[config]
        new = value + travel + waiting
        better = np.flatnonzero(ok & ~table.settled[:-1] & (new < table.dist[:-1]))
        table.improve(better, new[better], config, n, "move", travel[better] + waiting)
        for act in self.acts(config):
            if act.kind == "push":
                if act.pose != n:
                    continue  # a push strokes from where the base stands
                step = travel_cost(self.point(n), self.point(act.end)) + W1 * act.after.waiting
            elif ok[act.pose] or act.pose == n:
                step = float(travel[act.pose]) + W1 * act.after.waiting
            else:
                continue
            after = tables.setdefault(act.after, _Table(len(self.cells) + 1))
            if not after.settled[act.end] and value + step < after.dist[act.end]:
                after.improve(np.array([act.end]), np.array([value + step]), config, n, act.kind, np.array([step]))

    def _path(self, tables: dict[Config, _Table], config: Config, n: int) -> tuple[Step, ...]:
        steps = []
        while tables[config].came[n] is not None:
            before, m, kind, cost = tables[config].came[n]
            steps.append(Step(kind, self.point(n), cost))
            config, n = before, m
        return tuple(reversed(steps))

    # ------------------------------------------------------------------ replay
    def replay(self, optimum: Optimum) -> None:
        """Check each step of ``optimum`` with the env's own functions (``move_refusal``, ``check_action``)."""
        scenario, lattice = self.scenario, self.lattice
        config = Config(-1, tuple(START for _ in scenario.objects), tuple(-1 for _ in self.pushable))
        base = scenario.robot.start
        for step in optimum.steps:
            if step.kind == "move":
                assert move_refusal(scenario, lattice, base, step.base) is None, (base, step)
            else:
                match = [a for a in self.acts(config) if a.kind == step.kind and self.point(a.end) == step.base]
                assert match, (config, step)
                pose = self.point(match[0].pose)
                if step.kind != "push":
                    assert move_refusal(scenario, lattice, base, pose) is None, (base, step)
                config = match[0].after
            base = step.base
        assert config.done


def _near_a_line(lattice: Lattice, point: Point) -> bool:
    """Whether ``point`` lies within the env's stroke alignment (1e-6 m) of a lattice line: only then may a push
    start there (``rules._check_push``); the search pushes from lattice points alone."""
    for axis in (0, 1):
        index = (point[axis] - lattice.origin[axis]) / lattice.resolution
        if abs(lattice.origin[axis] + round(index) * lattice.resolution - point[axis]) <= 1e-6:
            return True
    return False


def _with(values: tuple[int, ...], index: int, value: int) -> tuple[int, ...]:
    return (*values[:index], value, *values[index + 1 :])


def _covers(rect: Rect, obj) -> bool:
    """Whether the piece of clutter stands on the object's goal (the paper's u_i)."""
    return rect.overlaps_disc(obj.goal, obj.radius)


def _pushed_rect(scenario: Scenario, lattice: Lattice, clutter_id: str, direction: str) -> Rect:
    """Where ``clutter_id`` stands after its minimal stroke along ``direction``."""
    rect = scenario.clutter_item(clutter_id).rect
    covered = [(o.goal, o.radius) for o in scenario.objects if _covers(rect, o)]
    stroke = push_stroke(rect, direction, covered, lattice.resolution)
    ux, uy = heading_vector(direction)
    return rect.translate(ux * stroke, uy * stroke)


def plan_task_cost(scenario: Scenario, phases) -> float:
    """The task cost of a plan's phases: travel plus ``W1`` per object not at its goal after each step (metres)."""
    total = 0.0
    for before, after in itertools.pairwise(phases):
        waiting = sum(
            1
            for obj in scenario.objects
            if after.holding == obj.id or math.dist(after.objects[obj.id][:2], obj.goal) > GOAL_TOL
        )
        total += travel_cost(before.base, after.base) + W1 * waiting
    return total


def plan_eq1(scenario: Scenario, phases) -> float:
    """The paper's Eq. 1 of a plan's phases: travel less ``W1`` per object at its goal at each phase (the start too)."""
    travel = sum(travel_cost(a.base, b.base) for a, b in itertools.pairwise(phases))
    delivered = sum(
        1
        for phase in phases
        for obj in scenario.objects
        if phase.holding != obj.id and math.dist(phase.objects[obj.id][:2], obj.goal) <= GOAL_TOL
    )
    return travel - W1 * delivered
