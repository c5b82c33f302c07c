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
from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import IndexBox, move_regions, point_in_move_region, start_tangents
from expert.milp.problem import Problem
from expert.milp.skeleton_graph import ActionGraph, SkeletonGraph, all_done, skeleton_moves
from fetchcarry_env.kinematics import WAIT_COST, travel_cost


def counting_bound(problem: Problem) -> int:
    """The action-counting lower bound on N (phases, the start included); see the module docstring."""
    holding = 1 if problem.holding is not None else 0
    pushes = len(problem.pushes.pushable)
    return 1 + 2 * len(problem.deliver) - holding + pushes


def settle(
    start: Hashable,
    expand: Callable[[Hashable], Iterable[tuple[float, Hashable]]],
    deadline: Deadline = NEVER,
    parents: dict | None = None,
) -> Iterator[tuple[float, Hashable]]:
    """Dijkstra's search: yield ``(cost, state)`` in order of least cost, each state once.

    ``expand(state)`` gives ``(step cost, next state)`` pairs; callers stop iterating when
    they have what they need. ``parents``, if given, receives each settled state's
    predecessor on its cheapest path. :func:`cheapest_schedule` searches with it, over
    states with their phase; the other bounds search the skeleton graph level by level
    (:mod:`expert.milp.skeleton_graph`).
    """
    best = {start: 0.0}
    queue = [(0.0, 0, start)]
    counter = 0
    while queue:
        cost, _, state = heapq.heappop(queue)
        if cost > best[state]:
            continue
        deadline.check()
        yield cost, state
        for step, nxt in expand(state):
            total = cost + step
            if total < best.get(nxt, math.inf) - 1e-12:
                best[nxt] = total
                if parents is not None:
                    parents[nxt] = state
                counter += 1
                heapq.heappush(queue, (total, counter, nxt))


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
    """One-move connectivity between base sets under Eq. 18 (the octagons of :func:`move_regions`).

    Optimistic where it must approximate (a box cut by a diagonal region is replaced by
    its bounding box), so that every bound built on it stays a lower bound.
    """

    def __init__(self, problem: Problem, deadline: Deadline = NEVER) -> None:
        scenario = problem.scenario
        radius = scenario.robot.radius
        self.start = scenario.robot.start
        self.domain = problem.grid.domain
        self.deadline = deadline
        rects = [t.rect for t in scenario.tables] + [o.rect for o in scenario.obstacles]
        self.blockers = []
        for rect in rects:
            deadline.check()
            planes = move_regions(problem.grid, rect, radius)
            if any(self.domain.inside(p) for p in planes):
                continue  # the rectangle lies outside the domain: no move can hit it
            regular = len(planes)
            at_start = tuple(
                n for n in range(regular) if point_in_move_region(problem.grid, self.start, rect, radius, n)
            )
            tangents = (
                start_tangents(problem.grid, self.start, rect, radius) if problem.grid.first_move_tangents else ()
            )  # as the MILP's first move
            planes = (*planes, *tangents)
            self.blockers.append((planes, at_start + tuple(range(regular, len(planes))), regular))
        self._from_start: dict = {}  # answers about the start: this problem's own
        geometry = (self.domain, tuple(planes[:regular] for planes, _, regular in self.blockers))
        self._between = _shared_memo(geometry)  # answers between two boxes: any problem of this geometry's

    def _memo(self, a: IndexBox | None) -> dict:
        """Where answers about moves from ``a`` are kept: the start's depend on it, the others on the geometry alone."""
        return self._from_start if a is None else self._between

    def _branches(self, a: IndexBox | None, w: IndexBox, depth: int):
        """The ways past blocker ``depth``: one ``(a, w)`` pair per usable region (clipped), or ``[(a, w)]``."""
        planes, at_start, regular = self.blockers[depth]
        regions = at_start if a is None else range(regular)
        usable = [n for n in regions if w.meets(planes[n]) and (a is None or a.meets(planes[n]))]
        if any(w.inside(planes[n]) and (a is None or a.inside(planes[n])) for n in usable):
            return [(a, w)]
        return [(None if a is None else a.clip(planes[n]), w.clip(planes[n])) for n in usable]

    def _walk(self, a: IndexBox | None, w: IndexBox) -> Iterator[IndexBox]:
        """Depth-first over the blockers (no recursion: thousands of obstacles): the leaves' ``w`` boxes."""
        stack = [(a, w, 0)]
        while stack:
            a, w, depth = stack.pop()
            if w.empty or (a is not None and a.empty):
                continue
            if depth == len(self.blockers):
                yield w
                continue
            self.deadline.check()
            stack.extend((a2, w2, depth + 1) for a2, w2 in reversed(self._branches(a, w, depth)))

    def connectable(self, a: IndexBox | None, b: IndexBox) -> bool:
        """True when one straight move can join a point of ``a`` (None: the exact start) to a point of ``b``."""
        memo, key = self._memo(a), (a, b)
        if key not in memo:
            memo[key] = next(self._walk(a, b), None) is not None
        return memo[key]

    def connectable_in_two(self, a: IndexBox | None, b: IndexBox) -> bool:
        """True when two straight moves can join ``a`` to ``b``: some lattice point is one move from both.

        Optimistic (True) when the sets one move away are too fragmented to list, so the
        bounds stay valid.
        """
        memo, key = self._memo(a), ("two", a, b)
        if key not in memo:
            from_a, from_b = self.one_move_from(a), self.one_move_from(b)
            memo[key] = True if from_a is None or from_b is None else any_overlap(from_a, from_b)
        return memo[key]

    def one_move_from(self, a: IndexBox | None) -> np.ndarray | None:
        """Boxes covering the free lattice points one move from ``a`` (None if more than ``MAX_PIECES``).

        One row ``(i_lo, i_hi, j_lo, j_hi)`` per box, none of them empty.
        """
        memo, key = self._memo(a), ("from", a)
        if key not in memo:
            pieces: list[IndexBox] = []
            for piece in self._walk(a, self.domain):
                pieces.append(piece)
                if len(pieces) > MAX_PIECES:
                    break
            rows = [(p.i_lo, p.i_hi, p.j_lo, p.j_hi) for p in pieces]
            memo[key] = None if len(pieces) > MAX_PIECES else np.array(rows, dtype=np.int64).reshape(-1, 4)
        return memo[key]


SHARED_GEOMETRIES = 4  # the geometries whose answers are kept between problems (the most recently used)
_SHARED: OrderedDict[Hashable, dict] = OrderedDict()


def _shared_memo(geometry: Hashable) -> dict:
    """The answers kept for one geometry (the domain and the blockers' regions), shared by every problem of it.

    The decoupled plan's sub-problems and the expert's replanning within one episode
    share their tables and obstacles, so each asks the same questions again; an answer
    depends on the geometry alone, so sharing it changes no bound. The
    ``SHARED_GEOMETRIES`` most recently used are kept.
    """
    memo = _SHARED.pop(geometry, None)
    _SHARED[geometry] = memo = {} if memo is None else memo
    while len(_SHARED) > SHARED_GEOMETRIES:
        _SHARED.popitem(last=False)
    return memo


def any_overlap(first: np.ndarray, second: np.ndarray) -> bool:
    """Whether a box of ``first`` and a box of ``second`` share a lattice point (rows ``i_lo, i_hi, j_lo, j_hi``).

    All pairs at once: the scalar ``not a.intersect(b).empty`` over every pair, as arrays.
    """
    if not len(first) or not len(second):
        return False
    a, b = first[:, None, :], second[None, :, :]
    meet_i = np.maximum(a[..., 0], b[..., 0]) <= np.minimum(a[..., 1], b[..., 1])
    meet_j = np.maximum(a[..., 2], b[..., 2]) <= np.minimum(a[..., 3], b[..., 3])
    return bool((meet_i & meet_j).any())


@dataclass(frozen=True)
class Skeleton:
    """What the skeleton relaxation proves: a lower bound on N and the earliest phase of each delivery.

    ``earliest[d]`` is the smallest phase by whose end ``d`` objects can be delivered
    (``earliest[0] = 0``); the MILP uses it as the valid inequality
    ``sum_i delta_{i,k} <= d - 1`` for ``k < earliest[d]`` (``expert.milp.objects``).
    """

    phases: int
    earliest: tuple[int, ...]


def skeleton(problem: Problem, pairs: PairCosts | None = None, deadline: Deadline = NEVER) -> Skeleton:
    """A lower bound on N from the order of actions and one-move connectivity (``docs/formulation.md``).

    Shortest path over the states (delivered, held, pushed, last pose) where each
    action costs the phases it needs at least: 1 when the previous pose (or the start)
    is joined to the action's pose by one straight move (Eq. 18), 2 otherwise; a push
    costs 1 more unless the previous pose can already be the stroke's start (a push
    acts from the previous phase's base). Poses are boxes of lattice points; taking
    any point of a box on entry and any on exit only makes the bound weaker, never wrong.
    The search is over ``pairs``' graph (:class:`expert.milp.skeleton_graph.SkeletonGraph`),
    which the other bounds share.
    """
    graph = (pairs or PairCosts(problem, deadline=deadline)).graph(deadline)
    phases = graph.least_from_start(graph.q.astype(float), deadline)
    count = len(problem.deliver)
    done = phases[graph.finished]
    if not done.size or not np.isfinite(done.min()):  # unreachable with a consistent problem: counting takes over
        return Skeleton(1 + 2 * count, tuple(2 * d for d in range(count + 1)))
    earliest = [phases[graph.delivered == d].min(initial=np.inf) for d in range(count + 1)]
    return Skeleton(1 + int(done.min()), tuple(int(e) if np.isfinite(e) else 2 * d for d, e in enumerate(earliest)))


def min_travel(problem: Problem, pairs: PairCosts | None = None, deadline: Deadline = NEVER) -> float:
    """A lower bound (metres) on the travel of any plan: the cheapest order of actions.

    The same graph as :func:`skeleton`'s, each step costed by ``travel_cost`` over the
    gap between the previous pose box (or the start) and the next (``travel_cost`` is a
    norm, so detours only add to it), plus a push's own stroke. The MILP states it as
    the valid inequality ``travel >= min_travel`` (``expert.milp.motion``).
    """
    graph = (pairs or PairCosts(problem, deadline=deadline)).graph(deadline)
    done = graph.least_from_start(graph.t, deadline)[graph.finished]
    return float(done.min()) if done.size and np.isfinite(done.min()) else 0.0


def min_objective(
    problem: Problem,
    n_phases: int,
    pair: PairCosts | None = None,
    deadline: Deadline = NEVER,
    last_at_end: bool = False,
) -> float:
    """A lower bound on the task cost of plans with ``n_phases`` phases (the skeleton search, timed).

    With ``t_i`` the phase of object ``i``'s delivery, the task cost is
    ``travel + W1 * sum_i (t_i - 1)`` (object ``i`` waits ``t_i - 1`` phases after the start;
    objects already delivered cost nothing): the MILP's objective, Eq. 1 up to a constant of
    the model. The search walks the skeleton's states extended by the phase reached, per pair
    of consecutive actions at the least phases and the least travel of any of their pose pairs
    (both lower bounds), adds ``W1 * t`` at each place, and stops at ``t <= N - 1``; the
    cheapest finished path minus ``W1 * n`` bounds the task cost from below. Returns ``-inf``
    when the search finds no path (no cut).

    ``last_at_end``: every plan's last action is a place at phase ``N - 1`` (``N - 1``
    phases admit no plan, :mod:`expert.milp.fewest`); a path's last place then counts
    ``W1 * (N - 1)``, wherever the relaxation could have made it earlier.
    """
    value, _ = cheapest_schedule(problem, n_phases, pair, deadline, last_at_end)
    return value


def cheapest_schedule(
    problem: Problem,
    n_phases: int,
    pair: PairCosts | None = None,
    deadline: Deadline = NEVER,
    last_at_end: bool = False,
) -> tuple[float, list[tuple[tuple[str, str], int]]]:
    """:func:`min_objective` and the schedule that attains it: ``[((kind, target), phase), ...]`` in order.

    The schedule is a relaxation's (phases and travel between actions are lower bounds),
    so it may not be feasible; the planner uses its order of actions as a first guess.
    """
    pair = pair or PairCosts(problem, deadline=deadline)
    constant = -WAIT_COST * len(problem.deliver)  # the task cost counts W1 (t - 1) for a delivery at phase t
    step = pair.step

    def expand(state):
        delivered, held, pushed, _, phase, where = state
        for key, (d, h, p) in skeleton_moves(problem, delivered, held, pushed):
            last = last_at_end and key[0] == "place" and all_done(problem, d, p)
            for entry, exit_box in pair.actions[key].poses:
                phases, travel = step(where, key[0], entry, exit_box)
                reached = phase + phases
                if reached > n_phases - 1:
                    continue
                if last:
                    reached = n_phases - 1
                bonus = WAIT_COST * reached if key[0] == "place" else 0.0
                yield travel + bonus, (d, h, p, key, reached, exit_box)

    start = (frozenset(), problem.holding, frozenset(), None, 0, None)
    parents: dict = {}
    for spent, state in settle(start, expand, deadline, parents=parents):
        if all_done(problem, state[0], state[2]):
            schedule = []
            while state != start:
                schedule.append((state[3], state[4]))
                state = parents[state]
            return spent + constant, schedule[::-1]
    return -math.inf, []


class PairCosts:
    """The cost of a skeleton step, least phases and least travel through one pose (cached), and the graph of them.

    Every bound of this module and of :mod:`expert.milp.conditional` searches the one
    :class:`~expert.milp.skeleton_graph.SkeletonGraph` that :meth:`graph` builds.
    """

    def __init__(self, problem: Problem, free: Connectivity | None = None, deadline: Deadline = NEVER) -> None:
        self.problem = problem
        self.actions = _actions_by_key(problem)
        self.free = free or Connectivity(problem, deadline)
        self.steps: dict = {}
        self._graph: SkeletonGraph | None = None

    def graph(self, deadline: Deadline = NEVER) -> SkeletonGraph:
        """The skeleton graph of the problem with these steps' costs (built on the first call, then kept)."""
        if self._graph is None:
            poses = {key: action.poses for key, action in self.actions.items()}
            self._graph = SkeletonGraph.build(self.problem, poses, self.step, deadline)
        return self._graph

    def step(self, where: IndexBox | None, kind: str, entry: IndexBox, exit_box: IndexBox) -> tuple[int, float]:
        """Least phases and least travel (metres) from base set ``where`` (None: the start) through one pose.

        The pose is entered at ``entry`` and left at ``exit_box``; a push's travel includes its stroke (cached).
        """
        key = (where, entry, exit_box)
        found = self.steps.get(key)
        if found is None:
            grid, start = self.problem.grid, self.problem.scenario.robot.start
            travel = _gap_cost(grid, start, where, entry)
            if kind == "push":
                travel += _gap_cost(grid, start, entry, exit_box, touching=True)
            found = self.steps[key] = (_step_cost(self.free, self.problem, where, kind, entry), travel)
        return found


def action_windows(
    problem: Problem,
    n_phases: int,
    pair: PairCosts | None = None,
    deadline: Deadline = NEVER,
    last_at_end: bool = False,
) -> Windows:
    """Per action ``(kind, target)``, the phases at which any plan with ``n_phases`` can do it.

    A plan passes through exactly one skeleton state right after each action; from that
    state ``s`` the action lies in ``[arrival(s), N - 1 - remaining(s)]``: ``arrival``, the
    least phases from the start to ``s`` over every order of actions, ``remaining`` the
    least phases its remaining actions need. Both use lower bounds on the phases between
    two actions, so no plan does an action outside the union of these ranges over its
    states (not their hull: a pick may be possible early, before a push, and late, after
    it, but not between); the MILP creates no option binary there. The same union over
    the states where another action ``b`` was done before (or not) gives the phases of
    the action given ``b`` (:attr:`Windows.given`).

    ``last_at_end``: every plan's last action is at phase ``N - 1`` (true when ``N - 1``
    phases admit no plan, :mod:`expert.milp.fewest`); an action done as the last one
    (its state is finished) is then at ``N - 1`` exactly, so an action that is always
    the last (the place of a single object) can only be at ``N - 1``.
    """
    graph = (pair or PairCosts(problem, deadline=deadline)).graph(deadline).actions
    q = graph.q.astype(float)
    arrival = graph.least_from_start(q, deadline)
    remaining = graph.least_to_end(q, graph.finished, float(n_phases), deadline)
    return _union_of_windows(problem, n_phases, graph, arrival, remaining, last_at_end)


def _union_of_windows(
    problem: Problem, n_phases: int, graph: ActionGraph, arrival: np.ndarray, remaining: np.ndarray, last_at_end: bool
) -> Windows:
    """:func:`action_windows`' union over the states reached within ``n_phases``: ``[arrival, N - 1 - remaining]``."""
    n, keys = n_phases, list(_actions_by_key(problem))
    index = {key: i for i, key in enumerate(keys)}
    reached = np.flatnonzero(arrival[1:] <= n) + 1  # the start (node 0) did no action
    key_of = np.array([index[graph.nodes[g][3]] for g in reached], dtype=np.intp)
    first, last = arrival[reached], n - 1 - remaining[reached]
    if last_at_end:  # the last action of a finished state is at N - 1
        first = np.where(graph.finished[reached] & (first <= n - 1), n - 1, first)
    phases = np.arange(n)
    at = ((phases >= np.maximum(first, 1)[:, None]) & (phases <= last[:, None])).astype(np.intp)
    done = _done_before(keys, index, [graph.nodes[g] for g in reached])
    windows: dict[tuple[str, str], frozenset[int]] = {}
    given: dict[tuple[tuple[str, str], tuple[str, str], bool], frozenset[int]] = {}
    for i, key in enumerate(keys):
        rows = key_of == i
        if not rows.any():
            continue
        windows[key] = _phases_of(at[rows].any(axis=0))
        for before, which in ((True, done[rows]), (False, ~done[rows])):
            hits = which.T.astype(np.intp) @ at[rows]  # per other action, the states' windows summed
            for j in np.flatnonzero(which.any(axis=0)):
                if j != i:
                    given[key, keys[j], before] = _phases_of(hits[j] > 0)
    return Windows(windows, given)


def _phases_of(mask: np.ndarray) -> frozenset[int]:
    return frozenset(np.flatnonzero(mask).tolist())


@dataclass(frozen=True)
class Windows:
    """The phases at which each action can happen (:func:`action_windows`).

    ``phases[(kind, target)]``: every phase at which some plan can do the action (an
    action absent from it cannot happen at all). ``given[(key, other, before)]``: the
    phases of ``key`` in the plans where ``other`` was done before it (``before``) or not;
    a missing entry means no such plan.
    """

    phases: dict[tuple[str, str], frozenset[int]]
    given: dict[tuple[tuple[str, str], tuple[str, str], bool], frozenset[int]]

    def allows(self, key: tuple[str, str], k: int) -> bool:
        """Whether some plan can do the action ``key`` at phase ``k``."""
        return k in self.phases.get(key, ())


def _done_before(keys: list[tuple[str, str]], index: dict, nodes: list[tuple]) -> np.ndarray:
    """``[s, j]``: whether action ``keys[j]`` was done before the action that led to skeleton node ``s``.

    A node is ``(delivered, held, pushed, last action)``: an object delivered was picked and
    placed, the one held was picked, a piece pushed was pushed; the last action itself is not before.
    """
    done = np.zeros((len(nodes), len(keys)), dtype=bool)
    for row, (delivered, held, pushed, key) in enumerate(nodes):
        before = [("pick", o) for o in delivered] + [("place", o) for o in delivered] + [("push", c) for c in pushed]
        if held is not None:
            before.append(("pick", held))
        done[row, [index[k] for k in before if k != key and k in index]] = True  # a held object has no pick
    return done


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


def _actions_by_key(problem: Problem) -> dict[tuple[str, str], _Action]:
    return {(a.kind, a.target): a for a in _skeleton_actions(problem)}


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
