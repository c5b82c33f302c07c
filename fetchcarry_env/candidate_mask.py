"""The candidate mask as array operations: :mod:`fetchcarry_env.phases`' rules over all candidates at once.

:class:`FastPhases` answers what :func:`fetchcarry_env.phases.enumerate_phases` answers
(the reference: one candidate at a time through :func:`fetchcarry_env.rules.check_action`
and :func:`fetchcarry_env.rules.move_stop`), decision for decision, in a few array
operations per kind:

* the reach tests (which posture puts the hand over the target from each pose), the
  arm-line tests (Eq. 19, Liang-Barsky clipping) and the base's swept-disc tests
  (``first_contact``'s Minkowski sum: two grown rectangles and four rounded corners)
  are the scalar formulas applied to arrays, operation for operation, so that every
  comparison sees the same floating-point numbers as the scalar code;
* the one test whose numpy and Python forms may differ in the last bit (a hypot against
  a threshold) is redone with :func:`math.hypot` wherever the two are within 1e-12 m of
  the threshold, and a candidate whose choice of item is not obvious (two objects or
  two pieces of clutter within reach of one pose) is decided by ``check_action`` itself;
* what depends on the scenario alone is cached once per scenario (which lattice points
  the base disc fits in the area at, where it may stand without a contact, the
  blockers as arrays, the waypoint cells), and what depends on the movable items
  (pick, place and approach candidates before the base's move) is cached per state of
  the items: a move changes only the base, so a step after a move recomputes only the
  swept-disc tests from the new base, the pushes and the edge moves.

Units: metres for points, lattice cells for indices.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, replace

import numpy as np

from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.geometry import EPS, HEADINGS, Rect, heading_vector, to_world_frame
from fetchcarry_env.kinematics import hand_blocker, push_contact, push_headings
from fetchcarry_env.observation import WorldState
from fetchcarry_env.phases import CORNERS, STILL, PhaseLayout, PhaseTable, inside_lattice
from fetchcarry_env.rules import CONTACT_SLACK, base_blockers, check_action, clutter_rect, move_stop
from fetchcarry_env.scenario import DeliveryObject, Scenario

ArrayLike = np.ndarray | float  # metres: an array, or one number broadcast against the others
REACH_TOL = 1e-3  # metres: Posture.reaches' default tolerance (the rules use the default)
ARM_TOL = 1e-6  # metres: arm_line_clear's tolerance
GUARD = 1e-12  # metres: a hypot this close to its threshold is redone with math.hypot
UNIT = np.array([heading_vector(h) for h in HEADINGS], dtype=np.int64)  # (4, 2): heading index -> unit vector
_FIELDS = ("index", "ci", "cj", "heading", "posture")  # an _Offers' arrays
PUSH_HEADING = np.array([[HEADINGS.index(h) for h in push_headings(d)] for d in HEADINGS], dtype=np.int64)  # (4, 3)


# ---------------------------------------------------------------------- vectorised geometry
def _clip(
    px: ArrayLike, py: ArrayLike, dx: ArrayLike, dy: ArrayLike, rect: tuple
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Liang-Barsky over arrays (geometry._clip): ``(valid, t0, t1)`` of ``p + t (dx, dy)`` in ``rect``.

    ``rect`` is ``(min_x, min_y, max_x, max_y)``, each an array or a number (metres). The
    scalar loop's four constraints, taken per axis: a constraint whose denominator is
    negative raises ``t0``, a positive one lowers ``t1``, a zero one (within 1e-15) only
    asks that the point be on its side; max and min do not care in which order.
    """
    x0, y0, x1, y1 = rect
    t0, t1, bad = 0.0, 1.0, False
    for d, low, high in ((dx, px - x0, x1 - px), (dy, py - y0, y1 - py)):
        zero = np.abs(d) <= 1e-15
        bad = bad | (zero & ((low < 0) | (high < 0)))
        safe = np.where(zero, 1.0, d)
        t_low, t_high = low / -safe, high / safe  # the constraints (-d, low) and (d, high)
        rising = d > 0
        t0 = np.where(zero, t0, np.maximum(t0, np.where(rising, t_low, t_high)))
        t1 = np.where(zero, t1, np.minimum(t1, np.where(rising, t_high, t_low)))
    return ~bad & (t0 <= t1), t0, t1


def _hypot_below(dx: np.ndarray, dy: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """``hypot(dx, dy) < limit`` elementwise, exactly as :func:`math.hypot` decides it (1-D arrays, metres)."""
    value = np.hypot(dx, dy)
    out = value < limit
    for i in np.flatnonzero(np.abs(value - limit) <= GUARD):
        out[i] = math.hypot(float(dx[i]), float(dy[i])) < float(limit[i])
    return out


def sweep_table(blockers: np.ndarray, radius: float) -> np.ndarray:
    """``(22, 2 M)``: what the swept-disc test needs of each blocker, for ``radius - CONTACT_SLACK`` then ``radius``.

    Per column: the rectangle (4), the disc's ``radius - EPS`` and ``radius ** 2`` (computed as
    ``radius * radius``), the two grown rectangles' ``min_x`` (2), ``min_y`` (2), ``max_x`` (2),
    ``max_y`` (2), and the four corners' x (4) and y (4), in the scalar code's order (metres).
    One row per quantity, so that the columns of the pairs tested gather into contiguous rows.
    """
    rows = []
    for r in (radius - CONTACT_SLACK, radius):
        x0, y0, x1, y1 = (blockers[:, i] for i in range(4))
        rows.append(
            np.stack(
                [
                    *(x0, y0, x1, y1, np.full(x0.shape, r - EPS), np.full(x0.shape, r * r)),
                    *(x0 - r, x0, y0, y0 - r, x1 + r, x1, y1, y1 + r),
                    *(x0, x1, x1, x0, y0, y0, y1, y1),
                ]
            )
        )
    return np.ascontiguousarray(np.concatenate(rows, axis=1).reshape(22, -1))


def _sweep_hits(px: ArrayLike, py: ArrayLike, qx: np.ndarray, qy: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """True where the disc of column ``n`` of a :func:`sweep_table` sliding ``p`` -> ``q`` touches its rectangle.

    geometry._sweep_disc_rect(...) < 1.0, operation for operation (1-D arrays, or one start
    point as numbers, metres): the start inside the rounded rectangle, an entry into one of
    the two grown rectangles or the four corner circles before ``t = 1``. The two
    rectangles, and the four circles, go through one array pass each.
    """
    x0, y0, x1, y1, limit, r2 = rows[:6]
    hit = _hypot_below(
        np.maximum(np.maximum(x0 - px, 0.0), px - x1), np.maximum(np.maximum(y0 - py, 0.0), py - y1), limit
    )
    dx, dy = qx - px, qy - py
    grown = rows[6:8], rows[8:10], rows[10:12], rows[12:14]  # (2, n) each
    valid, t0, t1 = _clip(px, py, dx, dy, grown)
    hit |= (valid & (t1 - t0 > EPS) & (t0 < 1.0)).any(axis=0)
    fx, fy = px - rows[14:18], py - rows[18:22]  # (4, n): from each corner
    a = dx * dx + dy * dy
    b = 2 * (fx * dx + fy * dy)
    disc = b * b - 4 * a * (fx * fx + fy * fy - r2)
    real = (a > 1e-18) & (disc > 0)
    root, two_a = np.sqrt(np.where(real, disc, 0.0)), np.where(real, 2 * a, 1.0)
    t_in, t_out = (-b - root) / two_a, (-b + root) / two_a
    return hit | (real & (t_out > EPS) & (t_in < 1.0)).any(axis=0)


def moves_free(
    start_x: ArrayLike,
    start_y: ArrayLike,
    end_x: ArrayLike,
    end_y: ArrayLike,
    radius: float,
    blockers: np.ndarray,
    table: np.ndarray | None = None,
) -> np.ndarray:
    """True where ``move_stop`` of a base of ``radius`` from start to end reports no contact (1-D arrays).

    ``blockers`` is ``(M, 4)``: ``rules.base_blockers``' rectangles as ``min_x, min_y,
    max_x, max_y`` (metres); ``table`` their :func:`sweep_table` (built here if not
    given). A blocker stops a move when the box around the move overlaps it and the
    swept discs of ``radius - CONTACT_SLACK`` and of ``radius`` both touch it (one array
    pass for the two). One start point (two numbers) is used as it is, not repeated per move.
    """
    table = sweep_table(blockers, radius) if table is None else table
    if np.ndim(start_x) == 0 and np.ndim(start_y) == 0:  # one start: every move leaves from it
        sx, sy = float(start_x), float(start_y)
        ex, ey = np.asarray(end_x, dtype=float), np.asarray(end_y, dtype=float)
        ex, ey = (ex, ey) if ex.shape == ey.shape else np.broadcast_arrays(ex, ey)
        starts = sx, sy
    else:
        sx, sy, ex, ey = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (start_x, start_y, end_x, end_y)))
        starts = None
    n, m = np.nonzero(
        _box_overlaps(
            sx if starts else sx[:, None],
            sy if starts else sy[:, None],
            ex[:, None],
            ey[:, None],
            radius,
            *(blockers[None, :, i] for i in range(4)),
        )
    )
    free = np.ones(ex.shape, dtype=bool)
    if n.size:
        both = np.concatenate((n, n))
        rows = table[:, np.concatenate((m, m + blockers.shape[0]))]
        px, py = starts if starts else (sx[both], sy[both])
        touch = _sweep_hits(px, py, ex[both], ey[both], rows).reshape(2, -1)
        free[n[touch.all(axis=0)]] = False
    return free


def _box_overlaps(
    sx: ArrayLike,
    sy: ArrayLike,
    ex: ArrayLike,
    ey: ArrayLike,
    radius: float,
    x0: ArrayLike,
    y0: ArrayLike,
    x1: ArrayLike,
    y1: ArrayLike,
) -> np.ndarray:
    """move_stop's first test: the box around every disc of the move overlaps the blocker (tol 0)."""
    box_x0, box_y0 = np.minimum(sx, ex) - radius, np.minimum(sy, ey) - radius
    box_x1, box_y1 = np.maximum(sx, ex) + radius, np.maximum(sy, ey) + radius
    return (np.minimum(box_x1, x1) - np.maximum(box_x0, x0) > 0.0) & (
        np.minimum(box_y1, y1) - np.maximum(box_y0, y0) > 0.0
    )


def _standing_blocked(px: np.ndarray, py: np.ndarray, radius: float, rects: np.ndarray) -> np.ndarray:
    """``moves_free``'s test of zero-length moves (``move_stop(p, p)``), per pair (point ``n``, ``rects[n]``).

    With ``q = p`` the sweep reduces to: the start inside the rounded rectangle, or
    inside one of the two closed grown rectangles (Liang-Barsky with zero denominators
    only asks ``low >= 0`` and ``high >= 0``; then ``t0 = 0``, ``t1 = 1``); the corner
    circles need a motion. The same comparisons as the scalar code, for both radii.
    """
    x0, y0, x1, y1 = (rects[:, i] for i in range(4))
    box = (np.minimum(px + radius, x1) - np.maximum(px - radius, x0) > 0.0) & (
        np.minimum(py + radius, y1) - np.maximum(py - radius, y0) > 0.0
    )
    blocked = box
    for r in (radius - CONTACT_SLACK, radius):
        near = np.maximum(np.maximum(x0 - px, 0.0), px - x1), np.maximum(np.maximum(y0 - py, 0.0), py - y1)
        touch = _hypot_below(*near, np.full(px.size, r - EPS))
        touch |= (px - (x0 - r) >= 0) & ((x1 + r) - px >= 0) & (py - y0 >= 0) & (y1 - py >= 0)
        touch |= (px - x0 >= 0) & (x1 - px >= 0) & (py - (y0 - r) >= 0) & ((y1 + r) - py >= 0)
        blocked = blocked & touch
    return blocked


def arm_crossings(px: ArrayLike, py: ArrayLike, qx: ArrayLike, qy: ArrayLike, rects: np.ndarray) -> np.ndarray:
    """``(N, R)``: True where the segment ``p`` - ``q`` crosses rectangle ``r`` of ``rects`` (``(R, 4)``, metres).

    ``segment_intersects_rect`` with ``arm_line_clear``'s tolerance: Liang-Barsky
    clipping against the rectangle shrunk by 1e-6 m.
    """
    px, py, qx, qy = (np.atleast_1d(np.asarray(v, dtype=float))[:, None] for v in np.broadcast_arrays(px, py, qx, qy))
    x0, y0, x1, y1 = (rects[:, i][None, :] + s for i, s in enumerate((ARM_TOL, ARM_TOL, -ARM_TOL, -ARM_TOL)))
    proper = (x0 < x1) & (y0 < y1)
    valid, _t0, _t1 = _clip(px, py, qx - px, qy - py, (x0, y0, x1, y1))
    return np.broadcast_to(proper & valid, (px.shape[0], rects.shape[0])).copy()


def arm_crosses(px: ArrayLike, py: ArrayLike, qx: ArrayLike, qy: ArrayLike, rects: np.ndarray) -> np.ndarray:
    """True where the segment ``p`` - ``q`` crosses one of ``rects`` (``(R, 4)``), as ``arm_line_clear`` decides."""
    return arm_crossings(px, py, qx, qy, rects).any(axis=1)


def _rects(rects: Iterable[Rect]) -> np.ndarray:
    """``(N, 4)`` array of rectangles (metres)."""
    return np.array([(r.min_x, r.min_y, r.max_x, r.max_y) for r in rects], dtype=float).reshape(-1, 4)


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

    def arm_rects(self, obstacles: np.ndarray, ignore: int | None) -> np.ndarray:
        """What the arm line may not cross: obstacles, then every piece but slot ``ignore`` (rules._arm_blocker)."""
        keep = np.arange(len(self.rects)) != (-1 if ignore is None else ignore)
        return np.concatenate([obstacles, self.array[keep]])


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
        area, margin = scenario.area, -radius  # check_action: area.contains_disc(target, radius, tol=1e-9)
        self.fits_x = (self.xs >= (area.min_x - margin) - 1e-9) & (self.xs <= (area.max_x + margin) + 1e-9)
        self.fits_y = (self.ys >= (area.min_y - margin) - 1e-9) & (self.ys <= (area.max_y + margin) + 1e-9)
        self.blockers = _rects(rect for _, rect in base_blockers(scenario))
        self.sweeps = sweep_table(self.blockers, radius)
        self.obstacles = _rects(o.rect for o in scenario.obstacles)
        postures = scenario.robot.postures
        self.reach = np.array(
            [
                (p.forward[0] - REACH_TOL, p.forward[1] + REACH_TOL, p.lateral[0] - REACH_TOL, p.lateral[1] + REACH_TOL)
                for p in postures
            ],
            dtype=float,
        ).reshape(-1, 4)
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
        self._stand = self._stand_grid()  # (nx, ny) bool: where the base may stand
        self._stops: dict = {}  # move_stop of a zero-length move at off-lattice points (push ends)
        self._waypoints = self._waypoint_cells()
        self._edges = self._edge_lines()
        self._edge_cells = self._edge_line_cells()
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
        bx, by = state.base
        keep = moves_free(bx, by, self.xs[ci], self.ys[cj], self.radius, self.blockers, self.sweeps)
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
        return _Pieces(
            rects,
            _rects(rects),
            np.array(contacts, dtype=float).reshape(-1, 4, 2),
            tables,
            np.array(
                [(t.rect.min_x, t.rect.min_y, t.rect.max_x, t.rect.max_y) if t else (np.nan,) * 4 for t in tables]
            ).reshape(-1, 4),
            np.array(hand_free, dtype=bool).reshape(-1, 4),
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
            offers = offers.take(self._fits(offers.ci, offers.cj) & self._stand_at(offers.ci, offers.cj))
            offers.mode = int(mode)
            keep = ~arm_crosses(
                self.xs[offers.ci], self.ys[offers.cj], target[0], target[1], pieces.arm_rects(self.obstacles, None)
            )
            if mode == Mode.PICK:
                keep &= self._picks_take(state, offers, slot)
            groups.append(offers.take(keep))
        return _concat(groups, int(mode))

    def _picks_take(self, state: WorldState, offers: _Offers, slot: int) -> np.ndarray:
        """True where the object nearest the posture's centre within reach is the candidate's own (_check_pick)."""
        scenario = self.scenario
        points = np.array([state.objects[o.id][:2] for o in scenario.objects], dtype=float)
        reaching = self._reaches_all(offers, points)
        keep = reaching.sum(axis=1) == 1  # only its own object in reach (it always reaches its own)
        for n in np.flatnonzero(~keep):
            action = Action(
                (int(offers.ci[n]), int(offers.cj[n])), HEADINGS[offers.heading[n]], int(offers.posture[n]), Mode.PICK
            )
            phase = check_action(scenario, state, self.lattice, action)
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
        on a table after the stroke, room for the hand, the arm line clear.
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
        cross = arm_crossings(
            px, py, pieces.contacts[c, d, 0], pieces.contacts[c, d, 1], pieces.arm_rects(self.obstacles, None)
        )
        cross[np.arange(c.size), self.obstacles.shape[0] + c] = False  # rules._arm_blocker ignores the pushed piece
        keep &= alone & ~cross.any(axis=1)
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
        """Approach, waypoint and edge moves allowed but for the swept-disc test and the one-per-action rule."""
        bx, by = state.base
        fixed_x, ix, in_x, jy, in_y, eindex = self._edge_cells
        ci_b, in_bx = self._cell_of(bx, 0)
        cj_b, in_by = self._cell_of(by, 1)
        inside = np.zeros(eindex.size, dtype=bool)  # the end (line's x, base's y) or (base's x, line's y) inside
        if in_by:
            inside |= in_x
        if in_bx:
            inside |= in_y
        ei = np.where(fixed_x, ix, ci_b)[inside]
        ej = np.where(fixed_x, cj_b, jy)[inside]
        eindex = eindex[inside]
        keep = self._fits(ei, ej) & self._stand_at(ei, ej)
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
        bx, by = state.base
        posture = self._first_posture(*_hand_offset(h, bx, by, pieces.contacts[c, d, 0], pieces.contacts[c, d, 1]))
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
        """rules._check_push from the base, then the stroke's end free and reached (``_offer``), per push candidate."""
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
        fwd, lat = _hand_offset(offers.heading[sel][:, None], bx, by, contacts[..., 0], contacts[..., 1])
        r = self.reach[offers.posture[sel]][:, None, :]
        single = ((r[..., 0] <= fwd) & (fwd <= r[..., 1]) & (r[..., 2] <= lat) & (lat <= r[..., 3])).sum(axis=1) == 1
        plain[sel[~single]] = False
        keep[sel[~single]] = False
        sel = sel[single]
        slot, way = c[sel], d[sel]
        t, rect = pieces.table_array[slot], pieces.array[slot]
        lx, ly = ux[sel] * length[sel], uy[sel] * length[sel]  # Rect.translate of the piece by the stroke
        ok = pieces.hand_free[slot, way] & (rect[:, 0] + lx >= t[:, 0] - 1e-6) & (rect[:, 1] + ly >= t[:, 1] - 1e-6)
        ok &= (rect[:, 2] + lx <= t[:, 2] + 1e-6) & (rect[:, 3] + ly <= t[:, 3] + 1e-6)  # NaN: no table, refused
        for piece, stroke in set(zip(slot[ok].tolist(), way[ok].tolist(), strict=True)):
            cx, cy = pieces.contacts[piece, stroke]
            if arm_crosses(bx, by, cx, cy, pieces.arm_rects(self.obstacles, piece))[0]:
                ok &= ~((slot == piece) & (way == stroke))
        ex, ey = bx + ux[sel] * length[sel], by + uy[sel] * length[sel]  # where the stroke ends (ResolvedPhase.base)
        ends = np.flatnonzero(ok)
        if ends.size:
            x, y = ex[ends], ey[ends]
            free = moves_free(
                np.r_[x, np.full(x.size, bx)],
                np.r_[y, np.full(y.size, by)],
                np.r_[x, x],
                np.r_[y, y],
                self.radius,
                self.blockers,
                self.sweeps,
            )
            ok[ends] = free[: x.size] & free[x.size :]  # stands free at the end, and gets there
        keep[sel] = ok
        for n in np.flatnonzero(aligned & ~plain):
            action = Action(
                (int(offers.ci[n]), int(offers.cj[n])), HEADINGS[offers.heading[n]], int(offers.posture[n]), Mode.PUSH
            )
            keep[n] = self._push_allowed(state, action, self.scenario.clutter[int(c[n])].id)
        return keep

    def _push_allowed(self, state: WorldState, action: Action, item: str) -> bool:
        """``_Enumerator._offer`` for a push: the env accepts it on ``item``, the stroke's end is free and reached."""
        phase = check_action(self.scenario, state, self.lattice, action)
        if isinstance(phase, str) or phase.target != item:
            return False
        end = phase.base
        if end not in self._stops:
            self._stops[end] = move_stop(self.scenario, end, end)[1] is None
        return self._stops[end] and move_stop(self.scenario, state.base, end)[1] is None

    # ------------------------------------------------------------------ helpers
    def _window_offers(
        self, first: ArrayLike, centers: ArrayLike, headings: ArrayLike, targets: ArrayLike
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
        fwd, lat = _hand_offset(h, self.xs[ci], self.ys[cj], targets[group, 0], targets[group, 1])
        posture = self._first_posture(fwd, lat)
        ok = posture >= 0
        return _Offers(index[ok], ci[ok], cj[ok], h[ok], posture[ok], -1), group[ok]

    def _first_posture(self, fwd: np.ndarray, lat: np.ndarray) -> np.ndarray:
        """The first posture whose ranges hold each robot-frame offset (metres), or -1 (``Posture.reaches``)."""
        r = self.reach
        ok = (
            (r[:, 0] <= fwd[:, None])
            & (fwd[:, None] <= r[:, 1])
            & (r[:, 2] <= lat[:, None])
            & (lat[:, None] <= r[:, 3])
        )
        return np.where(ok.any(axis=1), ok.argmax(axis=1), -1)

    def _reaches_all(self, offers: _Offers, points: np.ndarray) -> np.ndarray:
        """``(N, J)``: True where candidate ``n``'s posture, from its pose, reaches point ``j`` (metres).

        ``points`` is ``(J, 2)``, or ``(N, J, 2)``: points per candidate.
        """
        h = offers.heading[:, None]
        points = points if points.ndim == 3 else points[None]
        fwd, lat = _hand_offset(
            h, self.xs[offers.ci][:, None], self.ys[offers.cj][:, None], points[..., 0], points[..., 1]
        )
        r = self.reach[offers.posture][:, None, :]
        return (r[..., 0] <= fwd) & (fwd <= r[..., 1]) & (r[..., 2] <= lat) & (lat <= r[..., 3])

    def _fits(self, ci: np.ndarray, cj: np.ndarray) -> np.ndarray:
        """True where the base disc at the lattice point fits in the area (check_action's first test)."""
        return self.fits_x[ci] & self.fits_y[cj]

    def _stand_at(self, ci: np.ndarray, cj: np.ndarray) -> np.ndarray:
        """True where a base standing at the lattice point fits in the area and touches nothing.

        ``check_action``'s area test and ``move_stop`` of a zero-length move there (every
        use asks both).
        """
        return self._stand[ci, cj]

    def _stand_grid(self) -> np.ndarray:
        """``(nx, ny)``: where the base fits in the area and a zero-length move reports no contact.

        Each blocker is tested at the lattice points of its window only (the points whose
        base box can overlap it, with a cell to spare): elsewhere no test can fail.
        """
        fits = self.fits_x[:, None] & self.fits_y[None, :]
        r, res = self.radius, self.lattice.resolution
        ii, jj, mm = [], [], []
        for m, (x0, y0, x1, y1) in enumerate(self.blockers.tolist()):
            i = np.flatnonzero(self.fits_x & (self.xs > x0 - r - res) & (self.xs < x1 + r + res))
            j = np.flatnonzero(self.fits_y & (self.ys > y0 - r - res) & (self.ys < y1 + r + res))
            gi, gj = np.meshgrid(i, j, indexing="ij")
            ii.append(gi.ravel())
            jj.append(gj.ravel())
            mm.append(np.full(gi.size, m))
        ii, jj, mm = np.concatenate(ii), np.concatenate(jj), np.concatenate(mm)
        x, y = self.xs[ii], self.ys[jj]
        blocked = _standing_blocked(x, y, r, self.blockers[mm])
        fits[ii[blocked], jj[blocked]] = False
        return fits

    def _waypoint_cells(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(ci, cj, candidate)`` of the waypoints that fit in the area and where the base may stand."""
        layout, lattice, res = self.layout, self.lattice, self.lattice.resolution
        first = round(self.radius / res)
        start, cells = layout.offsets["waypoint"], layout.corner_cells
        rows = []
        for slot, rect in self._blocker_slots():
            for corner, (sx, sy) in enumerate(CORNERS):
                cx = rect.max_x if sx > 0 else rect.min_x
                cy = rect.max_y if sy > 0 else rect.min_y
                for i in range(layout.corner_cells):
                    for j in range(layout.corner_cells):
                        point = (cx + sx * (first + i) * res, cy + sy * (first + j) * res)
                        if inside_lattice(lattice, point):
                            rows.append(
                                (*_index(lattice, point), start + ((slot * 4 + corner) * cells + i) * cells + j)
                            )
        ci, cj, index = (
            (np.array(v, dtype=np.int64) for v in zip(*rows, strict=True)) if rows else (np.zeros(0, int),) * 3
        )
        keep = self._fits(ci, cj) & self._stand_at(ci, cj)
        return ci[keep], cj[keep], index[keep]

    def _edge_lines(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(x, y, candidate)`` of every edge move's line: x for a line across x (y NaN: the base's), or y."""
        layout, lattice, res = self.layout, self.lattice, self.lattice.resolution
        half, (nx, ny) = res / 2, lattice.shape
        ox, oy = lattice.origin
        self._inside = (ox - half, oy - half, ox + (nx - 1) * res + half, oy + (ny - 1) * res + half)
        first = round(self.radius / res)
        start = layout.offsets["edge"]
        rows = []
        for slot, rect in self._blocker_slots():
            for side, heading in enumerate(HEADINGS):
                ux, uy = heading_vector(heading)
                for i in range(layout.corner_cells):
                    out = (first + i) * res
                    if ux:
                        line = (rect.max_x + out if ux > 0 else rect.min_x - out, math.nan)
                    else:
                        line = (math.nan, rect.max_y + out if uy > 0 else rect.min_y - out)
                    rows.append((*line, start + (slot * 4 + side) * layout.corner_cells + i))
        x, y, index = (np.array(v, dtype=float) for v in zip(*rows, strict=True)) if rows else (np.zeros(0),) * 3
        return x, y, index.astype(np.int64)

    def _edge_line_cells(self) -> tuple:
        """What of the edge moves depends on their lines alone: ``(fixed_x, i, in_x, j, in_y, candidate)``.

        ``fixed_x``: the line is across x (else across y); ``i``: the x lines' lattice column,
        ``in_x``: an x line within the lattice's cells; ``j``, ``in_y`` the same of the y lines.
        An edge move ends on its line at the base's other coordinate: the lattice cell along
        the line's own axis and whether it lies within the lattice's cells there are the
        line's (``_moves`` completes them with the base's).
        """
        ex, ey, eindex = self._edges
        fixed_x = ~np.isnan(ex)  # a line across x: the end's x is the line's, its y the base's
        lo_x, lo_y, hi_x, hi_y = self._inside
        x, y = np.where(fixed_x, ex, 0.0), np.where(fixed_x, 0.0, ey)
        i, j = self._cells(x, 0), self._cells(y, 1)
        in_x = fixed_x & (x >= lo_x) & (x <= hi_x)
        in_y = ~fixed_x & (y >= lo_y) & (y <= hi_y)
        return fixed_x, i, in_x, j, in_y, eindex

    def _cells(self, values: np.ndarray, axis: int) -> np.ndarray:
        """The lattice index along ``axis`` of each coordinate (metres): nearest, clipped (as Lattice.index)."""
        origin, res, count = self.lattice.origin[axis], self.lattice.resolution, self.lattice.shape[axis]
        return np.minimum(np.maximum(np.rint((values - origin) / res), 0), count - 1).astype(np.int64)

    def _cell_of(self, value: float, axis: int) -> tuple[int, bool]:
        """:meth:`_cells` of one coordinate (metres), and whether it lies within the lattice's cells on that axis."""
        low, high = self._inside[axis], self._inside[axis + 2]
        return int(self._cells(np.array([value], dtype=float), axis)[0]), bool(low <= value <= high)

    def _blocker_slots(self) -> list:
        """``(slot, rectangle)`` of every table and obstacle (``_Enumerator._blockers``)."""
        scenario, tables = self.scenario, self.layout.capacity.tables
        return [(k, t.rect) for k, t in enumerate(scenario.tables)] + [
            (tables + k, o.rect) for k, o in enumerate(scenario.obstacles)
        ]


def _index(lattice: Lattice, point: tuple[float, float]) -> tuple[int, int]:
    """``Lattice.index`` without numpy's scalar overhead: the nearest lattice point's ``(i, j)``, clipped."""
    (ox, oy), res, (nx, ny) = lattice.origin, lattice.resolution, lattice.shape
    return (min(max(round((point[0] - ox) / res), 0), nx - 1), min(max(round((point[1] - oy) / res), 0), ny - 1))


def _hand_offset(
    h: np.ndarray, bx: ArrayLike, by: ArrayLike, tx: ArrayLike, ty: ArrayLike
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
