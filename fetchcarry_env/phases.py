"""Candidate phases: a fixed, numbered list of the phases a learner may choose, with exact masks.

The env's own action is a ``MultiDiscrete`` grid of absolute lattice points, whose
per-component masks cannot say "no pick here". This module numbers a fixed list of
*candidate phases* instead, relative to the things in the world, and decides which of
them are possible from a state by asking the env's own rules
(:func:`fetchcarry_env.rules.check_action`, which holds the move, pose and arm rules),
never a copy of them. Each candidate stands for one env action; a candidate is
*allowed* when

1. its slot is filled (the object, piece of clutter or blocker exists) and its pose
   lies on the lattice,
2. ``check_action`` accepts its env action, acting on the candidate's own item (a pick
   candidate for object 0 whose pose would make the env take object 1 is not allowed;
   the env refuses a move that breaks the move rule, so an allowed candidate's base
   reaches its end and touches nothing), and
3. no earlier candidate of the list has the same env action (so that allowed
   candidates and the env actions they stand for are one to one), and
4. it is not a move that goes nowhere (to the point where the base stands: it would
   change nothing, and a deterministic learner that picks it once picks it forever).

The list, in this order (``o``: object slot, ``c``: clutter slot, ``h``: heading index
in ``+x, +y, -x, -y``, ``d``: push direction in the same order, ``k``: index into
:func:`fetchcarry_env.kinematics.push_headings` ``(d)``, ``f``/``l``: forward/lateral
offsets in lattice cells, robot frame; ``s``: stroke in cells):

============  ==============================  =====================================================
kind          numbered by                     env action
============  ==============================  =====================================================
``pick``      ``o, h, f, l``                  pick, heading ``h``, base ``f`` cells behind and ``l``
                                              cells right of object ``o``'s lattice cell, first
                                              posture that reaches it
``place``     ``o, h, f, l``                  place, the same poses around object ``o``'s goal
``push``      ``c, d, k, s``                  push from where the base stands, ``s`` cells along
                                              ``d``, heading ``push_headings(d)[k]``
``approach``  ``c, d, k, f, l``               move to a pose around the push contact of clutter
                                              ``c`` along ``d`` from which the env would accept a
                                              one-cell push of ``c`` along ``d`` at that heading
``waypoint``  ``b, corner, i, j``             move to the lattice point ``i``, ``j`` cells outward
                                              from the first one beyond both sides of a corner of
                                              blocker ``b`` (tables, then obstacles) grown by the
                                              robot's radius: the way around it
``edge``      ``b, side, i``                  move straight along x or y to the lattice line ``i``
                                              cells outward from the first one beyond side ``side``
                                              (in heading order) of blocker ``b`` grown by the
                                              radius: to get clear of it
============  ==============================  =====================================================

:func:`enumerate_phases` is the reference: one candidate at a time, through the rules
themselves. :class:`fetchcarry_env.candidate_mask.FastPhases`, which
:class:`~fetchcarry_env.phase_env.PhaseActions` uses, computes the same table (mask,
env actions, numbering) in array operations, a transcription of the same tests;
``tests/env/test_phase_mask_fast.py`` compares the two on random walks of every family.

Moves keep the current heading (every later phase turns to its own). Nothing here
filters on what the hand holds: that is the rules' business, so a change of the rules
(a push made while holding an object, say) changes the allowed candidates by itself.

Units: metres for points, lattice cells for offsets.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.geometry import HEADINGS, Heading, Point, Rect, heading_vector, to_world_frame
from fetchcarry_env.kinematics import push_contact, push_headings
from fetchcarry_env.observation import Capacity, WorldState
from fetchcarry_env.regions import in_reach, index_at_least, index_at_most
from fetchcarry_env.rules import check_action, clutter_rect
from fetchcarry_env.scenario import DEFAULT_POSTURES, Posture, Scenario

KINDS: tuple[str, ...] = ("pick", "place", "push", "approach", "waypoint", "edge")
REACH_TOL = 1e-3  # metres beyond the postures' ranges that the pose windows hold (more than the env's reach needs)
STILL = 1e-9  # metres: a move whose end is this close to the base goes nowhere


@dataclass(frozen=True)
class Candidate:
    """One numbered candidate, decoded (see the module docstring for the meaning of each field)."""

    kind: str
    slot: int  # object slot (pick, place), clutter slot (push, approach), blocker slot (waypoint, edge)
    heading: int  # pick/place: heading; push/approach: index k into push_headings(d); waypoint: corner; edge: side
    direction: int  # push/approach: stroke direction (heading index); else -1
    a: int  # pick/place/approach: forward cells; push: stroke cells; waypoint: outward x cells; edge: outward cells
    b: int  # pick/place/approach: lateral cells; push, edge: 0; waypoint: outward y cells


@dataclass(frozen=True)
class PhaseLayout:
    """The fixed numbering of the candidates: how many of each kind, in which order.

    ``forward`` is the nearest and farthest forward offset (lattice cells) of a pose from
    its target's lattice cell, ``lateral`` the largest lateral offset either side;
    :meth:`for_postures` sizes them so that every lattice pose from which a posture
    reaches a target is in the window. ``strokes`` is the longest push stroke (cells);
    ``corner_cells`` how many outward offsets per axis a waypoint corner has.
    """

    capacity: Capacity = field(default_factory=Capacity)
    forward: tuple[int, int] = (7, 14)  # lattice cells
    lateral: int = 1  # lattice cells
    strokes: int = 6  # lattice cells
    corner_cells: int = 2

    def __post_init__(self) -> None:
        if not 0 <= self.forward[0] <= self.forward[1]:
            raise ValueError(f"forward must be (near, far) with 0 <= near <= far cells, got {self.forward}")
        if self.lateral < 0 or self.strokes < 1 or self.corner_cells < 1:
            raise ValueError("lateral must be >= 0, strokes and corner_cells >= 1")

    @classmethod
    def for_postures(
        cls, postures: Sequence[Posture] = DEFAULT_POSTURES, resolution: float = 0.05, **options
    ) -> PhaseLayout:
        """The layout whose pose windows hold every lattice pose from which one of ``postures`` reaches a target.

        A target lies at most half a cell from its lattice cell, so a pose ``f`` cells in
        front of that cell is ``f * resolution`` metres ahead, give or take half a cell.
        """
        if not postures:
            raise ValueError("at least one posture is needed")
        if resolution <= 0:
            raise ValueError(f"resolution must be positive, got {resolution}")
        near = min(p.forward[0] for p in postures) - REACH_TOL
        far = max(p.forward[1] for p in postures) + REACH_TOL
        side = max(max(abs(p.lateral[0]), abs(p.lateral[1])) for p in postures) + REACH_TOL
        forward = (max(0, math.ceil(near / resolution - 0.5)), math.floor(far / resolution + 0.5))
        return cls(forward=forward, lateral=math.floor(side / resolution + 0.5), **options)

    # ------------------------------------------------------------------ shapes
    @property
    def window(self) -> tuple[int, int]:
        """``(forward values, lateral values)`` of a pose window."""
        return (self.forward[1] - self.forward[0] + 1, 2 * self.lateral + 1)

    @property
    def blockers(self) -> int:
        """Blocker slots: the capacity's tables, then its obstacles."""
        return self.capacity.tables + self.capacity.obstacles

    def shape(self, kind: str) -> tuple[int, ...]:
        """The index shape of one kind (its candidates are numbered in C order over it)."""
        nf, nl = self.window
        shapes = {
            "pick": (self.capacity.objects, len(HEADINGS), nf, nl),
            "place": (self.capacity.objects, len(HEADINGS), nf, nl),
            "push": (self.capacity.clutter, len(HEADINGS), 3, self.strokes),
            "approach": (self.capacity.clutter, len(HEADINGS), 3, nf, nl),
            "waypoint": (self.blockers, 4, self.corner_cells, self.corner_cells),
            "edge": (self.blockers, len(HEADINGS), self.corner_cells),
        }
        if kind not in shapes:
            raise ValueError(f"unknown candidate kind {kind!r}; known: {', '.join(KINDS)}")
        return shapes[kind]

    @cached_property
    def offsets(self) -> dict[str, int]:
        """The index of each kind's first candidate."""
        out, start = {}, 0
        for kind in KINDS:
            out[kind] = start
            start += int(np.prod(self.shape(kind)))
        return out

    @cached_property
    def size(self) -> int:
        """K, the number of candidates (the ``Discrete(K)`` action space)."""
        return sum(int(np.prod(self.shape(kind))) for kind in KINDS)

    def kind_slice(self, kind: str) -> slice:
        """The indices of one kind's candidates."""
        start = self.offsets[kind]
        return slice(start, start + int(np.prod(self.shape(kind))))

    def index(self, kind: str, *coords: int) -> int:
        """The number of the candidate of ``kind`` at ``coords`` (its :meth:`shape`'s C-order index)."""
        index = 0
        for value, size in zip(coords, self.shape(kind), strict=True):
            if not 0 <= value < size:
                raise ValueError(f"{kind} coordinates {coords} are outside the shape {self.shape(kind)}")
            index = index * size + value
        return self.offsets[kind] + index

    def describe(self, index: int) -> Candidate:
        """The candidate numbered ``index``; ``ValueError`` outside ``[0, size)``."""
        if not 0 <= index < self.size:
            raise ValueError(f"candidate {index} is outside [0, {self.size})")
        for kind in reversed(KINDS):
            start = self.offsets[kind]
            if index >= start:
                coords = [int(v) for v in np.unravel_index(index - start, self.shape(kind))]
                break
        if kind in ("pick", "place"):
            slot, heading, f, lat = coords
            return Candidate(kind, slot, heading, -1, self.forward[0] + f, lat - self.lateral)
        if kind == "push":
            slot, direction, k, s = coords
            return Candidate(kind, slot, k, direction, s + 1, 0)
        if kind == "approach":
            slot, direction, k, f, lat = coords
            return Candidate(kind, slot, k, direction, self.forward[0] + f, lat - self.lateral)
        if kind == "waypoint":
            slot, corner, i, j = coords
            return Candidate(kind, slot, corner, -1, i, j)
        slot, side, i = coords
        return Candidate(kind, slot, side, -1, i, 0)


class PhaseTable:
    """The candidates of one state: which are allowed, and the env action of each allowed one.

    ``mask`` is ``(K,)`` bool; ``actions`` ``(K, 5)`` int64, the ``MultiDiscrete`` env action
    of each allowed candidate (zeros elsewhere); ``lookup`` maps an env action (a tuple)
    to the allowed candidate standing for it, built from the two when first asked for
    if not given.
    """

    def __init__(self, mask: np.ndarray, actions: np.ndarray, lookup: dict[tuple[int, ...], int] | None = None) -> None:
        self.mask, self.actions, self._lookup = mask, actions, lookup

    @property
    def lookup(self) -> dict[tuple[int, ...], int]:
        """Env action -> the allowed candidate standing for it."""
        if self._lookup is None:
            allowed = np.flatnonzero(self.mask)
            self._lookup = dict(zip(map(tuple, self.actions[allowed].tolist()), allowed.tolist(), strict=True))
        return self._lookup

    def index_of(self, action: np.ndarray | Sequence[int] | Action) -> int | None:
        """The allowed candidate whose env action is ``action``, or None."""
        vector = action.to_array() if isinstance(action, Action) else np.asarray(action)
        return self.lookup.get(tuple(int(v) for v in vector))


CORNERS: tuple[tuple[int, int], ...] = ((-1, -1), (1, -1), (1, 1), (-1, 1))
"""Outward directions of a rectangle's corners, in waypoint order: min-min, max-min, max-max, min-max."""


def side_line(lattice: Lattice, rect: Rect, radius: float, side: Heading, cells: int) -> tuple[int, int]:
    """``(axis, index)`` of the lattice line ``cells`` outward from the first one beyond side ``side`` of ``rect``.

    ``rect`` is grown by ``radius``; the first line beyond its side is the first whose
    lattice points lie in that side's move region (the planner's exact rounding,
    :func:`fetchcarry_env.regions.side_regions`).
    """
    ux, uy = heading_vector(side)
    axis, sign = (0, ux) if ux else (1, uy)
    if sign > 0:
        first = index_at_least(lattice, axis, rect.max[axis] + radius)
    else:
        first = index_at_most(lattice, axis, rect.min[axis] - radius)
    return axis, first + sign * cells


def waypoint_cell(lattice: Lattice, rect: Rect, radius: float, corner: int, i: int, j: int) -> tuple[int, int]:
    """The lattice point of waypoint ``(corner, i, j)`` of ``rect``: beyond both sides of that corner (unclipped).

    It lies in two side regions of ``rect`` grown by ``radius``, so outside its octagon,
    and a move from anywhere in either region reaches it (as far as ``rect`` goes).
    """
    sx, sy = CORNERS[corner]
    return (
        side_line(lattice, rect, radius, "+x" if sx > 0 else "-x", i)[1],
        side_line(lattice, rect, radius, "+y" if sy > 0 else "-y", j)[1],
    )


def enumerate_phases(layout: PhaseLayout, scenario: Scenario, state: WorldState, lattice: Lattice) -> PhaseTable:
    """Which candidates are allowed in ``state`` (see the module docstring), and their env actions.

    The reference computation (a few to tens of milliseconds a state): the fast mask of
    :mod:`fetchcarry_env.candidate_mask` must give the same table.
    """
    return _Enumerator(layout, scenario, state, lattice).run()


class _Enumerator:
    """One enumeration: the state and the table being filled."""

    def __init__(self, layout: PhaseLayout, scenario: Scenario, state: WorldState, lattice: Lattice) -> None:
        self.layout, self.scenario, self.state, self.lattice = layout, scenario, state, lattice
        self.mask = np.zeros(layout.size, dtype=bool)
        self.actions = np.zeros((layout.size, 5), dtype=np.int64)
        self.lookup: dict[tuple[int, ...], int] = {}
        self._heading = HEADINGS.index(state.heading)

    def run(self) -> PhaseTable:
        self._acts("pick", [self.state.objects[o.id][:2] for o in self.scenario.objects], Mode.PICK)
        self._acts("place", [o.goal for o in self.scenario.objects], Mode.PLACE)
        self._pushes()
        self._approaches()
        self._waypoints()
        self._edges()
        return PhaseTable(self.mask, self.actions, self.lookup)

    # ------------------------------------------------------------------ kinds
    def _acts(self, kind: str, targets: list[Point], mode: Mode) -> None:
        """Pick or place candidates: poses in the window around each target, with the first posture reaching it."""
        layout = self.layout
        for slot, (target, obj) in enumerate(zip(targets, self.scenario.objects, strict=True)):
            center = self.lattice.index(target)
            for h, heading in enumerate(HEADINGS):
                for f, lat, cell in self._window(center, heading):
                    posture = self._posture(self.lattice.point(*cell), heading, target)
                    if posture is None:
                        continue
                    action = Action(cell, heading, posture, mode)
                    self._offer(layout.index(kind, slot, h, f, lat), action, obj.id)

    def _pushes(self) -> None:
        """Push candidates: strokes from where the base stands, against each piece of clutter."""
        layout = self.layout
        base = self.state.base
        here = self.lattice.index(base)
        for slot, item in enumerate(self.scenario.clutter):
            rect = clutter_rect(self.scenario, self.state, item.id)
            for d, direction in enumerate(HEADINGS):
                contact = push_contact(rect, direction)
                ux, uy = heading_vector(direction)
                for k, heading in enumerate(push_headings(direction)):
                    posture = self._posture(base, heading, contact)
                    if posture is None:
                        continue
                    for s in range(1, layout.strokes + 1):
                        cell = (here[0] + ux * s, here[1] + uy * s)
                        if not self._on_lattice(cell):
                            break
                        action = Action(cell, heading, posture, Mode.PUSH)
                        self._offer(layout.index("push", slot, d, k, s - 1), action, item.id)

    def _approaches(self) -> None:
        """Moves to the poses from which the env would accept a push of the piece along the direction.

        The env's own check decides, for a base standing at the pose: a one-cell push of
        the candidate's piece along ``d`` at heading ``push_headings(d)[k]``.
        """
        layout = self.layout
        for slot, item in enumerate(self.scenario.clutter):
            rect = clutter_rect(self.scenario, self.state, item.id)
            for d, direction in enumerate(HEADINGS):
                contact = push_contact(rect, direction)
                center = self.lattice.index(contact)
                ux, uy = heading_vector(direction)
                for k, heading in enumerate(push_headings(direction)):
                    for f, lat, cell in self._window(center, heading):
                        pose = self.lattice.point(*cell)
                        posture = self._posture(pose, heading, contact)
                        if posture is None:
                            continue
                        stroke_end = (cell[0] + ux, cell[1] + uy)
                        if not self._on_lattice(stroke_end):
                            continue
                        push = Action(stroke_end, heading, posture, Mode.PUSH)
                        index = layout.index("approach", slot, d, k, f, lat)
                        self._offer(
                            index, self._move(cell), None, lambda p=pose, a=push, i=item.id: self._pushes_from(p, a, i)
                        )

    def _pushes_from(self, pose: Point, push: Action, item: str) -> bool:
        """True when the env would accept ``push`` on ``item`` from a base standing at ``pose``."""
        there = replace(self.state, base=pose, heading=push.heading)
        phase = check_action(self.scenario, there, self.lattice, push)
        return not isinstance(phase, str) and phase.target == item

    def _waypoints(self) -> None:
        """Moves to the lattice points just beyond each corner of each table and obstacle (the way around it)."""
        layout, radius = self.layout, self.scenario.robot.radius
        for slot, rect in self._blockers():
            for corner in range(len(CORNERS)):
                for i in range(layout.corner_cells):
                    for j in range(layout.corner_cells):
                        cell = waypoint_cell(self.lattice, rect, radius, corner, i, j)
                        if self._on_lattice(cell):
                            self._offer(layout.index("waypoint", slot, corner, i, j), self._move(cell), None)

    def _edges(self) -> None:
        """Straight moves from the base, along x or y, to the lattice lines just beyond each side of each blocker."""
        layout, radius = self.layout, self.scenario.robot.radius
        here = self.lattice.index(self.state.base)
        for slot, rect in self._blockers():
            for side, heading in enumerate(HEADINGS):
                for i in range(layout.corner_cells):
                    axis, line = side_line(self.lattice, rect, radius, heading, i)
                    cell = (line, here[1]) if axis == 0 else (here[0], line)
                    if self._on_lattice(cell):
                        self._offer(layout.index("edge", slot, side, i), self._move(cell), None)

    def _blockers(self) -> list[tuple[int, Rect]]:
        """``(slot, rectangle)`` of every table and obstacle (tables first, as in the observation)."""
        rects = [(k, t.rect) for k, t in enumerate(self.scenario.tables)]
        return rects + [(self.layout.capacity.tables + k, o.rect) for k, o in enumerate(self.scenario.obstacles)]

    # ------------------------------------------------------------------ helpers
    def _window(self, center: tuple[int, int], heading: Heading) -> Iterator[tuple[int, int, tuple[int, int]]]:
        """``(f index, l index, cell)`` of the poses around ``center`` facing it at ``heading`` (on the lattice)."""
        layout = self.layout
        nf, nl = layout.window
        for f in range(nf):
            for lat in range(nl):
                dx, dy = to_world_frame(heading, layout.forward[0] + f, lat - layout.lateral)
                cell = (center[0] - int(dx), center[1] - int(dy))
                if self._on_lattice(cell):
                    yield f, lat, cell

    def _posture(self, base: Point, heading: Heading, point: Point) -> int | None:
        """The first of the robot's postures that puts the hand over ``point`` from the base pose, or None.

        The env's reach (:func:`fetchcarry_env.regions.in_reach`).
        """
        for k, posture in enumerate(self.scenario.robot.postures):
            if in_reach(self.lattice, base, heading, posture, point):
                return k
        return None

    def _move(self, cell: tuple[int, int]) -> Action:
        return Action(cell, HEADINGS[self._heading], 0, Mode.MOVE)

    def _move_key(self, cell: tuple[int, int]) -> tuple[int, ...]:
        return (cell[0], cell[1], self._heading, 0, int(Mode.MOVE))

    def _on_lattice(self, cell: tuple[int, int]) -> bool:
        return 0 <= cell[0] < self.lattice.shape[0] and 0 <= cell[1] < self.lattice.shape[1]

    def _offer(self, index: int, action: Action, target: str | None, also: Callable[[], bool] | None = None) -> None:
        """Allow candidate ``index`` if the env accepts ``action`` on ``target``, and it is the action's first.

        ``also`` is a further condition, asked once the cheap tests have passed.
        """
        key = (action.cell[0], action.cell[1], HEADINGS.index(action.heading), action.posture, int(action.mode))
        if key in self.lookup:
            return
        phase = check_action(self.scenario, self.state, self.lattice, action)
        if isinstance(phase, str) or (target is not None and phase.target != target):
            return
        if phase.mode == Mode.MOVE and math.dist(phase.base, self.state.base) <= STILL:
            return  # a move that goes nowhere does nothing: not a phase worth choosing
        if also is not None and not also():
            return
        self.mask[index] = True
        self.actions[index] = key
        self.lookup[key] = index
