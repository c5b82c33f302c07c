"""The candidate mask as array operations: :mod:`fetchcarry_env.phases`' rules over all candidates at once.

:class:`FastPhases` answers what :func:`fetchcarry_env.phases.enumerate_phases` answers
(the reference: one candidate at a time through :func:`fetchcarry_env.rules.check_action`),
decision for decision, in a few array operations per kind:

* the reach tests (which posture puts the hand over the target from each pose) are the
  scalar formulas applied to arrays, operation for operation, so that every comparison
  sees the same floating-point numbers as the scalar code;
* the move, pose and arm rules (:func:`fetchcarry_env.rules.move_refusal`,
  :func:`~fetchcarry_env.rules.pose_refusal`, :func:`~fetchcarry_env.rules.arm_refusal`)
  test lattice points against the regions' exact integer rows
  (:mod:`fetchcarry_env.regions`) as bit sets: which regions of each table's and
  obstacle's octagon hold a lattice point is computed once per scenario, for every
  lattice point; points off the lattice (the start, a base after a jammed push) and hand
  points are tested by the scalar functions' own comparisons;
* a candidate whose choice of item is not obvious (two objects or two pieces of clutter
  within reach of one pose) is decided by ``check_action`` itself;
* what depends on the scenario alone is cached once per scenario (which lattice points
  the base disc fits in the area at, the octagons' regions at every lattice point, the
  waypoint cells), and what depends on the movable items (pick, place and approach
  candidates before the base's move) is cached per state of the items: a move changes
  only the base, so a step after a move recomputes only the move rule from the new
  base, the pushes and the edge moves.

Units: metres for points, lattice cells for indices.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, replace

import numpy as np

from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.geometry import EPS, HEADINGS, Point, Rect, heading_vector, to_world_frame
from fetchcarry_env.kinematics import hand_blocker, push_contact, push_headings
from fetchcarry_env.observation import WorldState
from fetchcarry_env.phases import CORNERS, STILL, PhaseLayout, PhaseTable, side_line, waypoint_cell
from fetchcarry_env.regions import (
    ALL_SIDES,
    GEOM_TOL,
    REGIONS,
    SIDES,
    area_domain,
    cells_bits,
    grid_bits,
    hands_bits,
    lattice_cell,
    octagon_bits,
    octagon_rows,
    side_bits,
    side_rows,
)
from fetchcarry_env.rules import check_action, clutter_rect, in_area, move_blockers
from fetchcarry_env.scenario import DeliveryObject, Scenario

UNIT = np.array([heading_vector(h) for h in HEADINGS], dtype=np.int64)  # (4, 2): heading index -> unit vector
_FIELDS = ("index", "ci", "cj", "heading", "posture")  # an _Offers' arrays
PUSH_HEADING = np.array([[HEADINGS.index(h) for h in push_headings(d)] for d in HEADINGS], dtype=np.int64)  # (4, 3)


def _rects(rects: Iterable[Rect]) -> np.ndarray:
    """``(N, 4)`` array of rectangles (metres)."""
    return np.array([(r.min_x, r.min_y, r.max_x, r.max_y) for r in rects], dtype=float).reshape(-1, 4)


def _side_rows(lattice: Lattice, rects: Iterable[Rect]) -> np.ndarray:
    """``(N, 4, 3)`` int64: the arm rule's side half-planes of each rectangle (``regions.side_rows``)."""
    return np.array([side_rows(lattice, r) for r in rects], dtype=np.int64).reshape(-1, len(SIDES), 3)


# ---------------------------------------------------------------------- the candidates
@dataclass
class _Offers:
    """Candidates that passed every test but the base's: numbers, end cells, heading, posture, mode (1-D arrays)."""

    index: np.ndarray
    ci: np.ndarray
    cj: np.ndarray
    heading: np.ndarray
    posture: np.ndarray
    mode: int

    def take(self, keep: np.ndarray) -> _Offers:
        return _Offers(
            self.index[keep], self.ci[keep], self.cj[keep], self.heading[keep], self.posture[keep], self.mode
        )


def _empty(mode: int) -> _Offers:
    nothing = np.zeros(0, dtype=np.int64)
    return _Offers(nothing, nothing, nothing, nothing, nothing, mode)


@dataclass
class _Pieces:
    """The clutter where a state has it, in slot order: footprints, push contacts, tables, room for the hand."""

    rects: list  # Rect per piece (rules.clutter_rect), metres
    array: np.ndarray  # (n, 4) the same rectangles, metres
    contacts: np.ndarray  # (n, 4, 2): push contact of each piece along each direction, metres
    tables: list  # the table under each piece, or None (Scenario.table_under_rect)
    table_array: np.ndarray  # (n, 4): the rectangle of each one's table (NaN: none), metres
    hand_free: np.ndarray  # (n, 4) bool: nothing leaves no room for the hand at the contact (rules.hand_blocker)
    arm_array: np.ndarray  # (A, 4): what the arm rule tests, obstacles then every piece (rules.arm_refusal), metres
    arm_rows: np.ndarray  # (A, 4, 3): their side half-planes in lattice indices


@dataclass
class _Items:
    """What the movable items decide, for one placement of objects and clutter and one hand (cached per state)."""

    picks: _Offers
    places: _Offers
    approaches: _Offers
    pieces: _Pieces


class FastPhases:
    """The candidates of one scenario's states, as :func:`~fetchcarry_env.phases.enumerate_phases` decides them.

    Build one per scenario (what depends on the scenario alone is computed here, once);
    :meth:`table` gives the :class:`~fetchcarry_env.phases.PhaseTable` of a state.
    """

    def __init__(self, layout: PhaseLayout, scenario: Scenario, lattice: Lattice) -> None:
        self.layout, self.scenario, self.lattice = layout, scenario, lattice
        res, (nx, ny) = lattice.resolution, lattice.shape
        self.xs = lattice.origin[0] + np.arange(nx) * res  # metres: lattice.point's x of each column
        self.ys = lattice.origin[1] + np.arange(ny) * res
        radius = scenario.robot.radius
        self.radius = radius
        domain = area_domain(lattice, scenario.area, radius)  # check_action's area test of the action's cell
        self.fits_x = (np.arange(nx) >= domain.i_lo) & (np.arange(nx) <= domain.i_hi)
        self.fits_y = (np.arange(ny) >= domain.j_lo) & (np.arange(ny) <= domain.j_hi)
        self.walls = [rect for _, rect in move_blockers(scenario)]  # the tables and obstacles the base moves around
        rows = np.array([octagon_rows(lattice, r, radius) for r in self.walls], dtype=np.int64)
        self.bits = grid_bits(rows.reshape(-1, REGIONS, 3), lattice.shape)  # (nx, ny, walls): octagon regions held
        fits = self.fits_x[:, None] & self.fits_y[None, :]
        self._stand = fits & (self.bits != 0).all(axis=2)  # in the area and outside every octagon
        self._act = fits & ((self.bits & ALL_SIDES) != 0).all(axis=2)  # and on a side of each (rules.pose_refusal)
        self.obstacles = _rects(o.rect for o in scenario.obstacles)
        self._obstacle_rows = _side_rows(lattice, (o.rect for o in scenario.obstacles))
        postures = scenario.robot.postures
        self.reach = np.array(  # Posture.reaches(tol=GEOM_TOL): the reach of a base off the lattice (regions.in_reach)
            [
                (p.forward[0] - GEOM_TOL, p.forward[1] + GEOM_TOL, p.lateral[0] - GEOM_TOL, p.lateral[1] + GEOM_TOL)
                for p in postures
            ],
            dtype=float,
        ).reshape(-1, 4)
        self.spans = np.array(  # (4 headings, postures, 4): max dx, min dx, max dy, min dy of regions.reach_box
            [[_offset_span(h, p) for p in postures] for h in HEADINGS], dtype=float
        ).reshape(len(HEADINGS), -1, 4)
        nf, nl = layout.window
        self.window = np.array(
            [
                [
                    [to_world_frame(h, layout.forward[0] + f, lat - layout.lateral) for lat in range(nl)]
                    for f in range(nf)
                ]
                for h in HEADINGS
            ]
        ).astype(np.int64)  # (4, nf, nl, 2): cells from a pose to its target, world frame
        self._waypoints = self._waypoint_cells()
        self._edges = self._edge_lines()
        self._items: dict = {}
        c, d, k = (a.ravel() for a in np.indices((len(scenario.clutter), 4, 3)))
        self._push_grid = (c, d, PUSH_HEADING[d, k])

    # ------------------------------------------------------------------ the table
    def table(self, state: WorldState) -> PhaseTable:
        """Which candidates are allowed in ``state`` and their env actions: :func:`enumerate_phases`' answer."""
        items = self._items_of(state)
        moves = self._moves(state, items.approaches, HEADINGS.index(state.heading))
        groups = [items.picks, items.places, moves]  # every candidate whose end is a lattice point, moves last
        index, ci, cj, heading, posture = (np.concatenate([getattr(g, f) for g in groups]) for f in _FIELDS)
        keep = self._reached(state.base, ci, cj)
        start = index.size - moves.index.size
        allowed = np.flatnonzero(keep[start:]) + start
        _, first = np.unique(ci[allowed] * self.lattice.shape[1] + cj[allowed], return_index=True)
        keep[allowed] = False
        keep[allowed[first]] = True  # one move candidate per env action: the first allowed
        mode = np.repeat([g.mode for g in groups], [g.index.size for g in groups])
        mask = np.zeros(self.layout.size, dtype=bool)
        actions = np.zeros((self.layout.size, 5), dtype=np.int64)
        rows = np.flatnonzero(keep)
        mask[index[rows]] = True
        actions[index[rows]] = np.stack([ci[rows], cj[rows], heading[rows], posture[rows], mode[rows]], axis=1)
        pushes = self._pushes(state, items.pieces)
        if pushes.index.size:
            mask[pushes.index] = True
            actions[pushes.index] = np.stack(
                [pushes.ci, pushes.cj, pushes.heading, pushes.posture, np.full(pushes.index.size, pushes.mode)], axis=1
            )
        return PhaseTable(mask, actions)

    def _reached(self, base: Point, ci: np.ndarray, cj: np.ndarray) -> np.ndarray:
        """True where the move rule lets the base go from ``base`` to lattice point ``(ci, cj)`` (rules.move_refusal).

        The ends are in the area (their candidates were kept only where the base fits);
        the base must be too, and share a region of every octagon with each end.
        """
        if not in_area(self.scenario, self.lattice, base):
            return np.zeros(ci.size, dtype=bool)
        return ((self.bits[ci, cj] & self._point_bits(base)) != 0).all(axis=1)

    def _point_bits(self, point: Point) -> np.ndarray:
        """``(walls,)`` uint8: the octagon regions of every table and obstacle that hold a base at ``point``."""
        cell = lattice_cell(self.lattice, point)
        if cell is not None:
            return self.bits[cell]
        return np.array([octagon_bits(self.lattice, r, self.radius, point) for r in self.walls], dtype=np.uint8)

    # ------------------------------------------------------------------ what the items decide
    def _items_of(self, state: WorldState) -> _Items:
        """The pick, place and approach candidates before the base's tests, cached per placement of the items."""
        held = state.holding  # the held object goes with the hand: nothing here depends on where it is
        key = (tuple(None if k == held else v for k, v in state.objects.items()), tuple(state.clutter.values()), held)
        items = self._items.get(key)
        if items is None:
            if len(self._items) > 256:
                self._items.clear()
            pieces = self._pieces(state)
            picks, places = self._acts(state, Mode.PICK, pieces), self._acts(state, Mode.PLACE, pieces)
            items = _Items(picks, places, self._approaches(state, pieces), pieces)
            self._items[key] = items
        return items

    def _pieces(self, state: WorldState) -> _Pieces:
        """The clutter of ``state``, as the push and arm tests need it."""
        scenario = self.scenario
        rects = [clutter_rect(scenario, state, c.id) for c in scenario.clutter]
        tables = [scenario.table_under_rect(rect) for rect in rects]
        contacts = [[push_contact(rect, d) for d in HEADINGS] for rect in rects]
        hand_free = [
            [not self._hand_blocked(state, rects, item.id, point) for point in row]
            for item, row in zip(scenario.clutter, contacts, strict=True)
        ]
        array = _rects(rects)
        return _Pieces(
            rects,
            array,
            np.array(contacts, dtype=float).reshape(-1, 4, 2),
            tables,
            np.array(
                [(t.rect.min_x, t.rect.min_y, t.rect.max_x, t.rect.max_y) if t else (np.nan,) * 4 for t in tables]
            ).reshape(-1, 4),
            np.array(hand_free, dtype=bool).reshape(-1, 4),
            np.concatenate([self.obstacles, array]),
            np.concatenate([self._obstacle_rows, _side_rows(self.lattice, rects)]),
        )

    def _acts(self, state: WorldState, mode: Mode, pieces: _Pieces) -> _Offers:
        """Pick (``mode`` PICK) or place candidates allowed but for the base's move (``_Enumerator._acts``)."""
        scenario, layout = self.scenario, self.layout
        if (state.holding is None) != (mode == Mode.PICK) or not scenario.objects:
            return _empty(int(mode))
        ids = [o.id for o in scenario.objects]
        slots = range(len(ids)) if mode == Mode.PICK else [ids.index(state.holding)]
        kind = "pick" if mode == Mode.PICK else "place"
        groups = []
        for slot in slots:
            obj = scenario.objects[slot]
            target = state.objects[obj.id][:2] if mode == Mode.PICK else obj.goal
            if mode == Mode.PLACE and _goal_taken(scenario, state, obj):
                continue
            first = layout.offsets[kind] + (slot * len(HEADINGS) + np.arange(len(HEADINGS))) * int(
                np.prod(layout.window)
            )
            offers, _g = self._window_offers(first, [_index(self.lattice, target)] * 4, np.arange(4), [target] * 4)
            offers = offers.take(self._act[offers.ci, offers.cj])  # in the area, on a side of every wall
            offers.mode = int(mode)
            keep = self._arm_clear(pieces, (offers.ci, offers.cj), (), ([target[0]], [target[1]]))
            if mode == Mode.PICK:
                keep &= self._picks_take(state, offers, slot)
            groups.append(offers.take(keep))
        return _concat(groups, int(mode))

    def _arm_clear(
        self,
        pieces: _Pieces,
        cells: tuple[np.ndarray, np.ndarray],
        more_cells: tuple[tuple[np.ndarray, np.ndarray], ...],
        *hands: tuple[np.ndarray, np.ndarray],
        ignore: np.ndarray | None = None,
    ) -> np.ndarray:
        """rules.arm_refusal for lattice bases, per candidate: True where every arm blocker has a common side.

        ``cells`` (and ``more_cells``: a stroke's other end) are the bases' lattice points,
        ``hands`` the hand points ``(x, y)`` (metres), one per candidate each; ``ignore`` the
        pushed piece's slot per candidate (its column is left out).
        """
        common = cells_bits(pieces.arm_rows, *cells)
        for more in more_cells:
            common &= cells_bits(pieces.arm_rows, *more)
        for hx, hy in hands:
            common &= hands_bits(pieces.arm_array, hx, hy)
        if ignore is not None:
            common[np.arange(ignore.size), self.obstacles.shape[0] + ignore] = ALL_SIDES
        return (common != 0).all(axis=1)

    def _picks_take(self, state: WorldState, offers: _Offers, slot: int) -> np.ndarray:
        """True where the object nearest the posture's centre within reach is the candidate's own (_check_pick).

        Where another object is in reach too, ``check_action`` decides from a base standing at
        the pose (what it takes does not depend on where the base comes from; the move there
        is tested per state, and this answer is cached per placement of the items).
        """
        scenario = self.scenario
        points = np.array([state.objects[o.id][:2] for o in scenario.objects], dtype=float)
        reaching = self._reaches_all(offers, points)
        keep = reaching.sum(axis=1) == 1  # only its own object in reach (it always reaches its own)
        for n in np.flatnonzero(~keep):
            cell = (int(offers.ci[n]), int(offers.cj[n]))
            action = Action(cell, HEADINGS[offers.heading[n]], int(offers.posture[n]), Mode.PICK)
            phase = check_action(scenario, replace(state, base=self.lattice.point(*cell)), self.lattice, action)
            keep[n] = not isinstance(phase, str) and phase.target == scenario.objects[slot].id
        return keep

    def _approaches(self, state: WorldState, pieces: _Pieces) -> _Offers:
        """Approach moves allowed but for the base's move and the still test (``_Enumerator._approaches``)."""
        scenario, layout, lattice = self.scenario, self.layout, self.lattice
        n = len(scenario.clutter)
        if n == 0:
            return _empty(int(Mode.MOVE))
        c, d, k = (a.ravel() for a in np.indices((n, 4, 3)))
        first = layout.offsets["approach"] + np.arange(c.size) * int(np.prod(layout.window))  # C order of (c, d, k)
        contacts = pieces.contacts
        targets = contacts[c, d]
        (ox, oy), res, (nx, ny) = lattice.origin, lattice.resolution, lattice.shape
        centers = np.stack(  # Lattice.index of every contact (np.rint rounds half to even, as round does)
            [
                np.clip(np.rint((targets[:, 0] - ox) / res), 0, nx - 1),
                np.clip(np.rint((targets[:, 1] - oy) / res), 0, ny - 1),
            ],
            axis=1,
        ).astype(np.int64)
        offers, g = self._window_offers(first, centers, PUSH_HEADING[d, k], targets)
        c, d = c[g], d[g]
        ux, uy = UNIT[d, 0], UNIT[d, 1]
        ei, ej = offers.ci + ux, offers.cj + uy
        on = (ei >= 0) & (ei < lattice.shape[0]) & (ej >= 0) & (ej < lattice.shape[1])
        offers, c, d, ux, uy, ei, ej = offers.take(on), c[on], d[on], ux[on], uy[on], ei[on], ej[on]
        keep = self._fits(offers.ci, offers.cj) & self._fits(ei, ej) & self._stand_at(offers.ci, offers.cj)
        keep &= self._pushes_from(state, offers, pieces, c, d, ei, ej)
        out = offers.take(keep)
        out.heading = np.full(
            out.index.size, HEADINGS.index(state.heading)
        )  # replaced by the heading of the state asked
        out.posture = np.zeros(out.index.size, dtype=np.int64)
        out.mode = int(Mode.MOVE)
        return out

    def _pushes_from(
        self,
        state: WorldState,
        offers: _Offers,
        pieces: _Pieces,
        c: np.ndarray,
        d: np.ndarray,
        ei: np.ndarray,
        ej: np.ndarray,
    ) -> np.ndarray:
        """True where the env would accept the one-cell push from the pose (``_Enumerator._pushes_from``).

        rules._check_push from a base at the pose, for the push of piece ``c`` along
        ``d`` to cell ``(ei, ej)``: the piece alone in reach (else check_action decides),
        on a table after the stroke, room for the hand, both ends of the stroke on one
        common side of every table and obstacle (the pose rule, which implies the move
        rule for the stroke), and the arm rule at both ends.
        """
        px, py = self.xs[offers.ci], self.ys[offers.cj]
        dx, dy = self.xs[ei] - px, self.ys[ej] - py
        dx, dy = np.where(np.abs(dx) <= 1e-6, 0.0, dx), np.where(np.abs(dy) <= 1e-6, 0.0, dy)
        length = np.abs(dx) + np.abs(dy)
        lx, ly = UNIT[d, 0] * length, UNIT[d, 1] * length  # Rect.translate of the piece by the stroke
        rect, t = pieces.array[c], pieces.table_array[c]  # NaN where no table: refused
        keep = pieces.hand_free[c, d] & (rect[:, 0] + lx >= t[:, 0] - 1e-6) & (rect[:, 1] + ly >= t[:, 1] - 1e-6)
        keep &= (rect[:, 2] + lx <= t[:, 2] + 1e-6) & (rect[:, 3] + ly <= t[:, 3] + 1e-6)
        alone = self._reaches_all(offers, pieces.contacts[:, d].transpose(1, 0, 2)).sum(axis=1) == 1
        keep &= alone & ((self.bits[offers.ci, offers.cj] & self.bits[ei, ej] & ALL_SIDES) != 0).all(axis=1)
        cx, cy = pieces.contacts[c, d, 0], pieces.contacts[c, d, 1]
        hand_end = cx + UNIT[d, 0] * length, cy + UNIT[d, 1] * length
        keep &= self._arm_clear(pieces, (offers.ci, offers.cj), ((ei, ej),), (cx, cy), hand_end, ignore=c)
        for n in np.flatnonzero(~alone):
            keep[n] = self._push_exact(state, offers, n, (int(ei[n]), int(ej[n])), self.scenario.clutter[int(c[n])].id)
        return keep

    def _push_exact(self, state: WorldState, offers: _Offers, n: int, end: tuple[int, int], item: str) -> bool:
        """``_Enumerator._pushes_from`` itself, for a pose from which more than one piece is within reach."""
        pose = (float(self.xs[offers.ci[n]]), float(self.ys[offers.cj[n]]))
        heading = HEADINGS[offers.heading[n]]
        there = replace(state, base=pose, heading=heading)
        phase = check_action(
            self.scenario, there, self.lattice, Action(end, heading, int(offers.posture[n]), Mode.PUSH)
        )
        return not isinstance(phase, str) and phase.target == item

    def _hand_blocked(self, state: WorldState, rects: list, item: str, contact: tuple[float, float]) -> bool:
        """True when something leaves no room for the hand at ``contact`` behind ``item`` (rules._check_push)."""
        scenario = self.scenario
        return (
            hand_blocker(
                contact,
                ((c.id, rect) for c, rect in zip(scenario.clutter, rects, strict=True) if c.id != item),
                ((o.id, state.objects[o.id][:2], o.radius) for o in scenario.objects if o.id != state.holding),
            )
            is not None
        )

    # ------------------------------------------------------------------ what the base decides
    def _moves(self, state: WorldState, approaches: _Offers, heading: int) -> _Offers:
        """Approach, waypoint and edge moves allowed but for the move rule and the one-per-action rule."""
        bx, by = state.base
        axis, line, eindex = self._edges
        here = _index(self.lattice, state.base)
        ei = np.where(axis == 0, line, here[0])  # an edge move ends on its line at the base's other coordinate
        ej = np.where(axis == 0, here[1], line)
        nx, ny = self.lattice.shape
        on = (ei >= 0) & (ei < nx) & (ej >= 0) & (ej < ny)
        ei, ej, eindex = ei[on], ej[on], eindex[on]
        keep = self._stand_at(ei, ej)
        wi, wj, windex = self._waypoints
        index = np.concatenate([approaches.index, windex, eindex[keep]])
        ci = np.concatenate([approaches.ci, wi, ei[keep]])
        cj = np.concatenate([approaches.cj, wj, ej[keep]])
        near = np.flatnonzero((np.abs(self.xs[ci] - bx) <= 1e-6) & (np.abs(self.ys[cj] - by) <= 1e-6))
        still = np.zeros(index.size, dtype=bool)
        for n in near:
            still[n] = math.dist((float(self.xs[ci[n]]), float(self.ys[cj[n]])), state.base) <= STILL
        size = index.size
        offers = _Offers(index, ci, cj, np.full(size, heading), np.zeros(size, dtype=np.int64), int(Mode.MOVE))
        return offers.take(~still)

    def _pushes(self, state: WorldState, pieces: _Pieces) -> _Offers:
        """The allowed push candidates (``_Enumerator._pushes``): strokes from the base, every test at once."""
        layout, lattice = self.layout, self.lattice
        if not self.scenario.clutter:
            return _empty(int(Mode.PUSH))
        c, d, h = self._push_grid  # (piece, direction, heading) of every push candidate's first stroke
        posture = self._first_posture_from(state.base, h, pieces.contacts[c, d, 0], pieces.contacts[c, d, 1])
        g = np.flatnonzero(posture >= 0)  # the strokes' (piece, direction, heading) whose contact is within reach
        if g.size == 0:
            return _empty(int(Mode.PUSH))
        strokes = np.arange(1, layout.strokes + 1)
        here = _index(lattice, state.base)
        ci = (here[0] + UNIT[d[g], 0][:, None] * strokes).ravel()
        cj = (here[1] + UNIT[d[g], 1][:, None] * strokes).ravel()
        index = (layout.offsets["push"] + g[:, None] * layout.strokes + strokes - 1).ravel()  # push's C order
        g = np.repeat(g, strokes.size)
        on = (ci >= 0) & (ci < lattice.shape[0]) & (cj >= 0) & (cj < lattice.shape[1])  # the loop's break
        offers = _Offers(index[on], ci[on], cj[on], h[g[on]], posture[g[on]], int(Mode.PUSH))
        offers = offers.take(self._fits(offers.ci, offers.cj))
        g = g[on][self._fits(ci[on], cj[on])]
        return offers.take(self._strokes_allowed(state, pieces, offers, c[g], d[g]))

    def _strokes_allowed(
        self, state: WorldState, pieces: _Pieces, offers: _Offers, c: np.ndarray, d: np.ndarray
    ) -> np.ndarray:
        """rules._check_push from the base, per push candidate: the piece, its table, the hand, the stroke's rules."""
        bx, by = state.base
        dx, dy = self.xs[offers.ci] - bx, self.ys[offers.cj] - by
        dx, dy = np.where(np.abs(dx) <= 1e-6, 0.0, dx), np.where(np.abs(dy) <= 1e-6, 0.0, dy)
        along_x, along_y = (np.abs(dy) <= EPS) & (np.abs(dx) > EPS), (np.abs(dx) <= EPS) & (np.abs(dy) > EPS)
        direction = np.where(along_x, np.where(dx > 0, 0, 2), np.where(along_y, np.where(dy > 0, 1, 3), -1))
        aligned = direction >= 0  # a zero or diagonal stroke is refused
        length = np.abs(dx) + np.abs(dy)
        ux, uy = UNIT[d, 0], UNIT[d, 1]
        keep = aligned & (direction == d)
        plain = keep.copy()  # decided here; the rest (another direction, two pieces in reach) by check_action
        sel = np.flatnonzero(keep)
        contacts = pieces.contacts[:, d[sel]].transpose(1, 0, 2)  # (S, pieces, 2): every piece's, along the stroke
        h, k = offers.heading[sel][:, None], offers.posture[sel][:, None]
        single = self._reach_from(state.base, h, k, contacts[..., 0], contacts[..., 1]).sum(axis=1) == 1
        plain[sel[~single]] = False
        keep[sel[~single]] = False
        sel = sel[single]
        slot, way = c[sel], d[sel]
        t, rect = pieces.table_array[slot], pieces.array[slot]
        lx, ly = ux[sel] * length[sel], uy[sel] * length[sel]  # Rect.translate of the piece by the stroke
        ok = pieces.hand_free[slot, way] & (rect[:, 0] + lx >= t[:, 0] - 1e-6) & (rect[:, 1] + ly >= t[:, 1] - 1e-6)
        ok &= (rect[:, 2] + lx <= t[:, 2] + 1e-6) & (rect[:, 3] + ly <= t[:, 3] + 1e-6)  # NaN: no table, refused
        ends = np.flatnonzero(ok)
        if ends.size:
            n = sel[ends]
            ok[ends] = self._stroke_clear(state.base, pieces, slot[ends], way[ends], length[n])
        keep[sel] = ok
        for n in np.flatnonzero(aligned & ~plain):
            action = Action(
                (int(offers.ci[n]), int(offers.cj[n])), HEADINGS[offers.heading[n]], int(offers.posture[n]), Mode.PUSH
            )
            keep[n] = self._push_allowed(state, action, self.scenario.clutter[int(c[n])].id)
        return keep

    def _stroke_clear(
        self, base: Point, pieces: _Pieces, slot: np.ndarray, way: np.ndarray, length: np.ndarray
    ) -> np.ndarray:
        """The stroke's rules from ``base`` (rules._check_push): moves, poses and the arm, per stroke.

        A stroke of piece ``slot`` along ``way`` of ``length`` metres ends at ``base + u *
        length`` (on the lattice when the base is, else tested by the scalar comparisons).
        """
        bx, by = base
        ux, uy = UNIT[way, 0], UNIT[way, 1]
        ex, ey = bx + ux * length, by + uy * length  # where the stroke ends (ResolvedPhase.base)
        ends = [(float(x), float(y)) for x, y in zip(ex.tolist(), ey.tolist(), strict=True)]
        start_bits = self._point_bits(base)
        ok = np.array([in_area(self.scenario, self.lattice, end) for end in ends], dtype=bool)
        ok &= in_area(self.scenario, self.lattice, base)
        end_bits = np.array([self._point_bits(end) for end in ends], dtype=np.uint8).reshape(len(ends), -1)
        ok &= ((start_bits & end_bits) != 0).all(axis=1)  # the move rule (Eq. 18)
        ok &= ((start_bits & end_bits & ALL_SIDES) != 0).all(axis=1)  # the pose rule: one common side
        common = self._arm_point_bits(pieces, base)[None, :] & np.array(
            [self._arm_point_bits(pieces, end) for end in ends], dtype=np.uint8
        ).reshape(len(ends), -1)
        cx, cy = pieces.contacts[slot, way, 0], pieces.contacts[slot, way, 1]
        hand_end = hands_bits(pieces.arm_array, cx + ux * length, cy + uy * length)
        common &= hands_bits(pieces.arm_array, cx, cy) & hand_end
        common[np.arange(slot.size), self.obstacles.shape[0] + slot] = ALL_SIDES  # the pushed piece is left out
        return ok & (common != 0).all(axis=1)

    def _arm_point_bits(self, pieces: _Pieces, point: Point) -> np.ndarray:
        """``(A,)`` uint8: the side half-planes of each arm blocker holding a base at ``point`` (rules.arm_refusal)."""
        cell = lattice_cell(self.lattice, point)
        if cell is not None:
            return cells_bits(pieces.arm_rows, [cell[0]], [cell[1]])[0]
        rects = [*(o.rect for o in self.scenario.obstacles), *pieces.rects]
        return np.array([side_bits(self.lattice, rect, point) for rect in rects], dtype=np.uint8)

    def _push_allowed(self, state: WorldState, action: Action, item: str) -> bool:
        """``_Enumerator._offer`` for a push: the env accepts it on ``item``."""
        phase = check_action(self.scenario, state, self.lattice, action)
        return not isinstance(phase, str) and phase.target == item

    # ------------------------------------------------------------------ helpers
    def _window_offers(
        self, first: np.ndarray | float, centers: np.ndarray | list, headings: np.ndarray, targets: np.ndarray | list
    ) -> tuple[_Offers, np.ndarray]:
        """The on-lattice poses of each group's window with the first posture reaching its target, and their group.

        Group ``g`` is the window of ``headings[g]`` around cell ``centers[g]``, numbered
        from candidate ``first[g]``, facing point ``targets[g]`` (``_Enumerator._window`` and ``_posture``).
        """
        first, headings = np.asarray(first, dtype=np.int64), np.asarray(headings, dtype=np.int64)
        centers, targets = np.asarray(centers, dtype=np.int64), np.asarray(targets, dtype=float)
        nf, nl = self.layout.window
        offsets = self.window[headings]  # (G, nf, nl, 2)
        ci = (centers[:, 0, None, None] - offsets[..., 0]).ravel()
        cj = (centers[:, 1, None, None] - offsets[..., 1]).ravel()
        index = (first[:, None, None] + np.arange(nf)[:, None] * nl + np.arange(nl)).ravel()
        group = np.repeat(np.arange(first.size), nf * nl)
        on = (ci >= 0) & (ci < self.lattice.shape[0]) & (cj >= 0) & (cj < self.lattice.shape[1])
        ci, cj, index, group = ci[on], cj[on], index[on], group[on]
        h = headings[group]
        postures = range(len(self.scenario.robot.postures))
        reach = [self._in_boxes(ci, cj, h, k, targets[group, 0], targets[group, 1]) for k in postures]
        posture = _first_true(reach, ci.size)
        ok = posture >= 0
        return _Offers(index[ok], ci[ok], cj[ok], h[ok], posture[ok], -1), group[ok]

    def _in_boxes(self, ci, cj, h, k, tx, ty) -> np.ndarray:
        """Whether lattice pose ``(ci, cj)`` lies in ``regions.reach_box`` of target ``(tx, ty)`` at heading ``h``
        with posture ``k`` (arrays broadcast together): the box's exact rounding, operation for operation."""
        (ox, oy), res = self.lattice.origin, self.lattice.resolution
        span = self.spans[h, k]  # (..., 4)
        lo_x, hi_x, lo_y, hi_y = tx - span[..., 0], tx - span[..., 1], ty - span[..., 2], ty - span[..., 3]
        return (
            (np.ceil((lo_x - GEOM_TOL - ox) / res - 1e-12) <= ci)
            & (ci <= np.floor((hi_x + GEOM_TOL - ox) / res + 1e-12))
            & (np.ceil((lo_y - GEOM_TOL - oy) / res - 1e-12) <= cj)
            & (cj <= np.floor((hi_y + GEOM_TOL - oy) / res + 1e-12))
        )

    def _reach_from(self, base: Point, h, k, tx, ty) -> np.ndarray:
        """``regions.in_reach`` from one base (the state's: on the lattice or not), for arrays of headings,
        postures and targets (metres) broadcast together."""
        cell = lattice_cell(self.lattice, base)
        if cell is not None:
            return self._in_boxes(cell[0], cell[1], h, k, tx, ty)
        fwd, lat = _hand_offset(h, base[0], base[1], tx, ty)
        r = self.reach[k]
        return (r[..., 0] <= fwd) & (fwd <= r[..., 1]) & (r[..., 2] <= lat) & (lat <= r[..., 3])

    def _first_posture_from(self, base: Point, h: np.ndarray, tx: np.ndarray, ty: np.ndarray) -> np.ndarray:
        """The first posture reaching each target from ``base`` at heading ``h`` (``_Enumerator._posture``), or -1."""
        postures = range(len(self.scenario.robot.postures))
        return _first_true([self._reach_from(base, h, np.full(h.shape, k), tx, ty) for k in postures], h.size)

    def _reaches_all(self, offers: _Offers, points: np.ndarray) -> np.ndarray:
        """``(N, J)``: True where candidate ``n``'s posture, from its pose, reaches point ``j`` (metres).

        ``points`` is ``(J, 2)``, or ``(N, J, 2)``: points per candidate.
        """
        points = points if points.ndim == 3 else points[None]
        return self._in_boxes(
            offers.ci[:, None],
            offers.cj[:, None],
            offers.heading[:, None],
            offers.posture[:, None],
            points[..., 0],
            points[..., 1],
        )

    def _fits(self, ci: np.ndarray, cj: np.ndarray) -> np.ndarray:
        """True where the base disc at the lattice point fits in the area (check_action's first test)."""
        return self.fits_x[ci] & self.fits_y[cj]

    def _stand_at(self, ci: np.ndarray, cj: np.ndarray) -> np.ndarray:
        """True where a base at the lattice point fits in the area and lies outside every octagon.

        Every move that ends there must have that end in the area and in a region of
        every octagon (rules.move_refusal): the test of the end alone, per lattice point.
        """
        return self._stand[ci, cj]

    def _waypoint_cells(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(ci, cj, candidate)`` of the waypoints on the lattice where a base may stand (:func:`waypoint_cell`)."""
        layout, lattice = self.layout, self.lattice
        start, cells = layout.offsets["waypoint"], layout.corner_cells
        (nx, ny), rows = lattice.shape, []
        for slot, rect in self._blocker_slots():
            for corner in range(len(CORNERS)):
                for i in range(cells):
                    for j in range(cells):
                        ci, cj = waypoint_cell(lattice, rect, self.radius, corner, i, j)
                        if 0 <= ci < nx and 0 <= cj < ny:
                            rows.append((ci, cj, start + ((slot * 4 + corner) * cells + i) * cells + j))
        ci, cj, index = (
            (np.array(v, dtype=np.int64) for v in zip(*rows, strict=True)) if rows else (np.zeros(0, int),) * 3
        )
        keep = self._stand_at(ci, cj)
        return ci[keep], cj[keep], index[keep]

    def _edge_lines(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(axis, line, candidate)`` of every edge move: its lattice line (:func:`side_line`) and its number."""
        layout, start = self.layout, self.layout.offsets["edge"]
        rows = []
        for slot, rect in self._blocker_slots():
            for side, heading in enumerate(HEADINGS):
                for i in range(layout.corner_cells):
                    axis, line = side_line(self.lattice, rect, self.radius, heading, i)
                    rows.append((axis, line, start + (slot * 4 + side) * layout.corner_cells + i))
        if not rows:
            return (np.zeros(0, dtype=np.int64),) * 3
        axis, line, index = (np.array(v, dtype=np.int64) for v in zip(*rows, strict=True))
        return axis, line, index

    def _blocker_slots(self) -> list:
        """``(slot, rectangle)`` of every table and obstacle (``_Enumerator._blockers``)."""
        scenario, tables = self.scenario, self.layout.capacity.tables
        return [(k, t.rect) for k, t in enumerate(scenario.tables)] + [
            (tables + k, o.rect) for k, o in enumerate(scenario.obstacles)
        ]


def _offset_span(heading: str, posture) -> tuple[float, float, float, float]:
    """``(max dx, min dx, max dy, min dy)`` of the posture's range corners at ``heading`` (``regions.reach_box``)."""
    offsets = [to_world_frame(heading, f, lat) for f in posture.forward for lat in posture.lateral]
    dxs, dys = [o[0] for o in offsets], [o[1] for o in offsets]
    return (max(dxs), min(dxs), max(dys), min(dys))


def _first_true(masks: list[np.ndarray], size: int) -> np.ndarray:
    """Per element, the index of the first mask that holds there, or -1."""
    out = np.full(size, -1, dtype=np.int64)
    for k in reversed(range(len(masks))):
        out = np.where(masks[k], k, out)
    return out


def _index(lattice: Lattice, point: tuple[float, float]) -> tuple[int, int]:
    """``Lattice.index`` without numpy's scalar overhead: the nearest lattice point's ``(i, j)``, clipped."""
    (ox, oy), res, (nx, ny) = lattice.origin, lattice.resolution, lattice.shape
    return (min(max(round((point[0] - ox) / res), 0), nx - 1), min(max(round((point[1] - oy) / res), 0), ny - 1))


def _hand_offset(
    h: np.ndarray, bx: np.ndarray | float, by: np.ndarray | float, tx: np.ndarray | float, ty: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray]:
    """``kinematics.hand_offset`` over arrays: robot-frame ``(forward, lateral)`` of the target (metres)."""
    dx, dy = tx - bx, ty - by
    hx, hy = UNIT[h, 0], UNIT[h, 1]
    return dx * hx + dy * hy, -dx * hy + dy * hx


def _concat(groups: list[_Offers], mode: int) -> _Offers:
    if not groups:
        return _empty(mode)
    return _Offers(
        *(np.concatenate([getattr(g, f) for g in groups]) for f in ("index", "ci", "cj", "heading", "posture")), mode
    )


def _goal_taken(scenario: Scenario, state: WorldState, obj: DeliveryObject) -> bool:
    """True when another object or a piece of clutter stands on ``obj``'s goal (rules._check_place)."""
    for other in scenario.objects:
        if other.id != obj.id and math.dist(state.objects[other.id][:2], obj.goal) < other.radius + obj.radius - 1e-9:
            return True
    return any(clutter_rect(scenario, state, item.id).overlaps_disc(obj.goal, obj.radius) for item in scenario.clutter)
