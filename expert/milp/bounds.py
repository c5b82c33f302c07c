"""Lower bounds on the number of phases, so the iterative deepening need not prove small N infeasible.

:func:`counting_bound` counts actions. Every object to deliver needs a pick and a
place (a held object only a place), every covering piece of clutter one push, each in
its own phase, plus phase 0:

    N >= 1 + 2 * (objects to deliver) - (1 if one is held) + (pieces to push).

(A push may be made while holding an object, so the first action may be a pick even
when every goal is covered: no phase is added for that.)
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

from expert.milp.grid import IndexBox, base_regions, point_in_region
from expert.milp.problem import Problem
from fetchcarry_env.kinematics import DELIVERY_BONUS, travel_cost


def counting_bound(problem: Problem) -> int:
    """The action-counting lower bound on N (phases, the start included); see the module docstring."""
    holding = 1 if problem.holding is not None else 0
    pushes = len(problem.pushes.pushable)
    return 1 + 2 * len(problem.deliver) - holding + pushes


def phase_lower_bound(problem: Problem) -> int:
    """The best proven lower bound on N: the larger of the counting and the skeleton bounds."""
    return max(3 if problem.deliver else 1, counting_bound(problem), skeleton(problem).phases)


# ---------------------------------------------------------------------- the skeleton bound
@dataclass(frozen=True)
class _Action:
    """An arm action of the skeleton and its poses: (entry, exit) base boxes.

    Entry: where the phase's acting base may be (a push acts from base_{k-1}, the stroke's
    start); exit: where the base is at the end of the action's phase.
    """

    kind: str
    target: str
    poses: tuple[tuple[IndexBox, IndexBox], ...]


MAX_PIECES = 256  # boxes listed for the points one move away before the two-move test gives up (optimistically)


class Connectivity:
    """One-move connectivity between base sets under Eq. 18 (tables and obstacles grown by the radius)."""

    def __init__(self, problem: Problem) -> None:
        scenario = problem.scenario
        radius = scenario.robot.radius
        self.start = scenario.robot.start
        self.domain = problem.grid.domain
        rects = [t.rect for t in scenario.tables] + [o.rect for o in scenario.obstacles]
        self.blockers = []
        for rect in rects:
            planes = base_regions(problem.grid, rect, radius)
            if any(self.domain.inside(p) for p in planes):
                continue  # the rectangle lies outside the domain: no move can hit it
            at_start = tuple(n for n in range(4) if point_in_region(self.start, rect, radius, n))
            self.blockers.append((planes, at_start))
        self._memo: dict = {}

    def connectable(self, a: IndexBox | None, b: IndexBox) -> bool:
        """True when one straight move can join a point of ``a`` (None: the exact start) to a point of ``b``."""
        key = (a, b)
        if key not in self._memo:
            self._memo[key] = self._search(a, b, 0)
        return self._memo[key]

    def _search(self, a: IndexBox | None, b: IndexBox, depth: int) -> bool:
        if b.empty or (a is not None and a.empty):
            return False
        if depth == len(self.blockers):
            return True
        planes, at_start = self.blockers[depth]
        regions = at_start if a is None else range(4)
        usable = [n for n in regions if b.meets(planes[n]) and (a is None or a.meets(planes[n]))]
        if any(b.inside(planes[n]) and (a is None or a.inside(planes[n])) for n in usable):
            return self._search(a, b, depth + 1)
        return any(self._search(None if a is None else a.clip(planes[n]), b.clip(planes[n]), depth + 1) for n in usable)

    def connectable_in_two(self, a: IndexBox | None, b: IndexBox) -> bool:
        """True when two straight moves can join ``a`` to ``b``: some lattice point is one move from both.

        Optimistic (True) when the sets one move away are too fragmented to list, so the
        bounds stay valid.
        """
        key = ("two", a, b)
        if key not in self._memo:
            from_a, from_b = self.one_move_from(a), self.one_move_from(b)
            if from_a is None or from_b is None:
                self._memo[key] = True
            else:
                self._memo[key] = any(not w.intersect(v).empty for w in from_a for v in from_b)
        return self._memo[key]

    def one_move_from(self, a: IndexBox | None) -> list[IndexBox] | None:
        """Boxes covering the free lattice points one move from ``a`` (None if more than ``MAX_PIECES``)."""
        key = ("from", a)
        if key not in self._memo:
            pieces: list[IndexBox] = []
            complete = self._spread(a, self.domain, 0, pieces)
            self._memo[key] = pieces if complete else None
        return self._memo[key]

    def _spread(self, a: IndexBox | None, w: IndexBox, depth: int, pieces: list[IndexBox]) -> bool:
        if w.empty or (a is not None and a.empty):
            return True
        if depth == len(self.blockers):
            pieces.append(w)
            return len(pieces) <= MAX_PIECES
        planes, at_start = self.blockers[depth]
        regions = at_start if a is None else range(4)
        usable = [n for n in regions if w.meets(planes[n]) and (a is None or a.meets(planes[n]))]
        if any(w.inside(planes[n]) and (a is None or a.inside(planes[n])) for n in usable):
            return self._spread(a, w, depth + 1, pieces)
        return all(
            self._spread(None if a is None else a.clip(planes[n]), w.clip(planes[n]), depth + 1, pieces) for n in usable
        )


@dataclass(frozen=True)
class Skeleton:
    """What the skeleton relaxation proves: a lower bound on N and the earliest phase of each delivery.

    ``earliest[d]`` is the smallest phase by whose end ``d`` objects can be delivered
    (``earliest[0] = 0``); the MILP uses it as the valid inequality
    ``sum_i delta_{i,k} <= d - 1`` for ``k < earliest[d]`` (``expert.milp.objects``).
    """

    phases: int
    earliest: tuple[int, ...]


def skeleton(problem: Problem, free: Connectivity | None = None) -> Skeleton:
    """A lower bound on N from the order of actions and one-move connectivity (``docs/formulation.md``).

    Shortest path over the states (delivered, held, pushed, last pose) where each
    action costs the phases it needs at least: 1 when the previous pose (or the start)
    is joined to the action's pose by one straight move (Eq. 18), 2 otherwise; a push
    costs 1 more unless the previous pose can already be the stroke's start (a push
    acts from the previous phase's base). Poses are boxes of lattice points; taking
    any point of a box on entry and any on exit only makes the bound weaker, never wrong.
    """
    actions = {(a.kind, a.target): a for a in _skeleton_actions(problem)}
    free = free or Connectivity(problem)
    deliver = problem.deliver
    pushable = problem.pushes.pushable
    start_state = (frozenset(), problem.holding, frozenset(), None)
    best = {start_state: 0}
    queue = [(0, 0, start_state)]
    counter = 0
    earliest: dict[int, int] = {0: 0}
    finished: int | None = None
    while queue:
        spent, _, state = heapq.heappop(queue)
        if spent > best.get(state, spent):
            continue
        delivered, held, pushed, where = state
        earliest.setdefault(len(delivered), spent)
        if finished is None and len(delivered) == len(deliver) and len(pushed) == len(pushable):
            finished = 1 + spent
        if finished is not None and len(earliest) == len(deliver) + 1:
            break
        moves = _moves(problem, delivered, held, pushed)
        for key, (d, h, p) in moves:
            action = actions[key]
            for entry, exit_box in action.poses:
                total = spent + _step_cost(free, problem, where, action.kind, entry)
                nxt = (d, h, p, exit_box)
                if total < best.get(nxt, total + 1):
                    best[nxt] = total
                    counter += 1
                    heapq.heappush(queue, (total, counter, nxt))
    if finished is None:  # unreachable with a consistent problem; the counting bound takes over
        return Skeleton(1 + 2 * len(deliver), tuple(2 * d for d in range(len(deliver) + 1)))
    return Skeleton(finished, tuple(earliest.get(d, 2 * d) for d in range(len(deliver) + 1)))


def _moves(problem: Problem, delivered: frozenset, held: str | None, pushed: frozenset) -> list:
    """The actions possible from a skeleton state: ``((kind, target), (delivered, held, pushed) after)``."""
    moves = []
    if held is not None:
        if all(c in pushed for c in problem.covers.get(held, ())):
            moves.append((("place", held), (delivered | {held}, None, pushed)))
    else:
        for object_id in problem.deliver:
            if object_id not in delivered:
                moves.append((("pick", object_id), (delivered, object_id, pushed)))
    for clutter_id in problem.pushes.pushable:  # with an empty hand or holding an object
        if clutter_id not in pushed:
            moves.append((("push", clutter_id), (delivered, held, pushed | {clutter_id})))
    return moves


def min_travel(problem: Problem) -> float:
    """A lower bound (metres) on the travel term of Eq. 1 of any plan: the cheapest order of actions.

    The same search as :func:`skeleton`, costing each step by ``travel_cost`` over the
    gap between the previous pose box (or the start) and the next (``travel_cost`` is a
    norm, so detours only add to it), plus a push's own stroke. The MILP states it as
    the valid inequality ``travel >= min_travel`` (``expert.milp.motion``).
    """
    actions = {(a.kind, a.target): a for a in _skeleton_actions(problem)}
    grid = problem.grid
    start = problem.scenario.robot.start
    pushable = problem.pushes.pushable
    start_state = (frozenset(), problem.holding, frozenset(), None)
    best = {start_state: 0.0}
    queue = [(0.0, 0, start_state)]
    counter = 0
    while queue:
        spent, _, state = heapq.heappop(queue)
        if spent > best.get(state, spent):
            continue
        delivered, held, pushed, where = state
        if len(delivered) == len(problem.deliver) and len(pushed) == len(pushable):
            return spent
        for key, (d, h, p) in _moves(problem, delivered, held, pushed):
            for entry, exit_box in actions[key].poses:
                step = _gap_cost(grid, start, where, entry)
                if key[0] == "push":
                    step += _gap_cost(grid, start, entry, exit_box, touching=True)
                nxt = (d, h, p, exit_box)
                total = spent + step
                if total < best.get(nxt, math.inf) - 1e-12:
                    best[nxt] = total
                    counter += 1
                    heapq.heappush(queue, (total, counter, nxt))
    return 0.0


def min_objective(problem: Problem, n_phases: int, pair: PairCosts | None = None) -> float:
    """A lower bound on Eq. 1 for plans with ``n_phases`` phases (the skeleton search, timed).

    With ``t_i`` the phase of object ``i``'s delivery, Eq. 1 is
    ``travel - W1 * sum_i (N - t_i)`` (``delta_{i,k} = 1`` from ``t_i`` on) plus the constant of
    objects already delivered. The search walks the skeleton's states extended by the
    phase reached, per pair of consecutive actions at the least phases and the least
    travel of any of their pose pairs (both lower bounds), adds ``W1 * t`` at each place,
    and stops at ``t <= N - 1``; the cheapest finished path minus ``W1 * n * N`` bounds
    Eq. 1 from below. Returns ``-inf`` when the search finds no path (no cut).
    """
    pair = pair or PairCosts(problem)
    count = len(problem.deliver)
    pushable = problem.pushes.pushable
    start_state = (frozenset(), problem.holding, frozenset(), None, 0)
    best = {start_state: 0.0}
    queue = [(0.0, 0, start_state)]
    counter = 0
    constant = -DELIVERY_BONUS * (count * n_phases + len(problem.delivered) * n_phases)
    while queue:
        spent, _, state = heapq.heappop(queue)
        if spent > best.get(state, spent):
            continue
        delivered, held, pushed, last, phase = state
        if len(delivered) == count and len(pushed) == len(pushable):
            return spent + constant
        for key, (d, h, p) in _moves(problem, delivered, held, pushed):
            phases, travel = pair(last, key)
            reached = phase + phases
            if reached > n_phases - 1:
                continue
            total = spent + travel + (DELIVERY_BONUS * reached if key[0] == "place" else 0.0)
            nxt = (d, h, p, key, reached)
            if total < best.get(nxt, math.inf) - 1e-12:
                best[nxt] = total
                counter += 1
                heapq.heappush(queue, (total, counter, nxt))
    return -math.inf


class PairCosts:
    """Least phases and least travel between two consecutive actions, over all their pose pairs (cached)."""

    def __init__(self, problem: Problem, free: Connectivity | None = None) -> None:
        self.problem = problem
        self.actions = {(a.kind, a.target): a for a in _skeleton_actions(problem)}
        self.free = free or Connectivity(problem)
        self.cache: dict = {}

    def __call__(self, previous: tuple[str, str] | None, key: tuple[str, str]) -> tuple[int, float]:
        if (previous, key) not in self.cache:
            problem, action = self.problem, self.actions[key]
            grid, start = problem.grid, problem.scenario.robot.start
            exits = [None] if previous is None else list(dict.fromkeys(e for _, e in self.actions[previous].poses))
            phases = min(_step_cost(self.free, problem, w, action.kind, en) for w in exits for en, _ in action.poses)
            travel = min(
                _gap_cost(grid, start, w, en)
                + (_gap_cost(grid, start, en, ex, touching=True) if action.kind == "push" else 0.0)
                for w in exits
                for en, ex in action.poses
            )
            self.cache[(previous, key)] = (phases, travel)
        return self.cache[(previous, key)]


def action_windows(
    problem: Problem, n_phases: int, pair: PairCosts | None = None
) -> dict[tuple[str, str], tuple[int, int]]:
    """Per action ``(kind, target)``, the phases ``[first, last]`` at which any plan with ``n_phases`` can do it.

    ``first``: the least phases from the start to the action over every order of actions
    (the skeleton search at action level); ``last``: ``N - 1`` minus the least phases
    still needed after it. Both use lower bounds on the phases between two actions, so
    no plan does an action outside its window; the MILP creates no option binary there.
    """
    pair = pair or PairCosts(problem)
    count, pushable = len(problem.deliver), len(problem.pushes.pushable)
    start_state = (frozenset(), problem.holding, frozenset(), None)
    arrival = {start_state: 0}
    queue = [(0, 0, start_state)]
    counter = 0
    while queue:
        phase, _, state = heapq.heappop(queue)
        if phase > arrival.get(state, phase):
            continue
        delivered, held, pushed, last = state
        for key, (d, h, p) in _moves(problem, delivered, held, pushed):
            reached = phase + pair(last, key)[0]
            nxt = (d, h, p, key)
            if reached < arrival.get(nxt, n_phases + 1):
                arrival[nxt] = reached
                counter += 1
                heapq.heappush(queue, (reached, counter, nxt))
    remaining: dict = {}

    def still_needed(state) -> int:
        if state not in remaining:
            delivered, held, pushed, last = state
            if len(delivered) == count and len(pushed) == pushable:
                remaining[state] = 0
            else:
                remaining[state] = min(
                    (
                        pair(last, key)[0] + still_needed((d, h, p, key))
                        for key, (d, h, p) in _moves(problem, delivered, held, pushed)
                    ),
                    default=n_phases,
                )
        return remaining[state]

    windows: dict[tuple[str, str], tuple[int, int]] = {}
    for state, phase in arrival.items():
        key = state[3]
        if key is None:
            continue
        first, last = windows.get(key, (n_phases, -1))
        windows[key] = (min(first, phase), max(last, n_phases - 1 - still_needed(state)))
    return windows


def _gap_cost(grid, start, a: IndexBox | None, b: IndexBox, touching: bool = False) -> float:
    """``travel_cost`` of the shortest vector from box ``a`` (None: the exact start) to box ``b``, metres.

    ``touching``: the exact displacement between two equal-sized boxes (a push's stroke).
    """
    res = grid.resolution
    if touching:
        dx, dy = (b.i_lo - a.i_lo) * res, (b.j_lo - a.j_lo) * res
    elif a is None:
        lo, hi = grid.point(b.i_lo, b.j_lo), grid.point(b.i_hi, b.j_hi)
        dx = max(lo[0] - start[0], 0.0, start[0] - hi[0])
        dy = max(lo[1] - start[1], 0.0, start[1] - hi[1])
    else:
        dx = max(b.i_lo - a.i_hi, 0, a.i_lo - b.i_hi) * res
        dy = max(b.j_lo - a.j_hi, 0, a.j_lo - b.j_hi) * res
    return travel_cost((0.0, 0.0), (dx, dy))


def _skeleton_actions(problem: Problem) -> list[_Action]:
    groups: dict[tuple[str, str], dict] = {}
    for option in problem.options:
        exit_box = option.box.shifted(*option.push.cells) if option.push is not None else option.box
        groups.setdefault((option.kind, option.target), {})[(option.box, exit_box)] = None
    return [_Action(kind, target, tuple(poses)) for (kind, target), poses in groups.items()]


def _step_cost(free: Connectivity, problem: Problem, where: IndexBox | None, kind: str, entry: IndexBox) -> int:
    """Phases needed at least from base set ``where`` (None: the start) to the end of an action entered at ``entry``."""
    moves = 1 if free.connectable(where, entry) else 2 if free.connectable_in_two(where, entry) else 3
    if kind != "push":
        return moves
    if where is None:
        if problem.start_index is not None and entry.contains(*problem.start_index):
            return 1
    elif not where.intersect(entry).empty:
        return 1
    return moves + 1
