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
from collections.abc import Callable, Hashable, Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import IndexBox
from expert.milp.moves import LeastMoves, problem_moves
from expert.milp.problem import Problem
from expert.milp.skeleton_graph import MAX_EDGES, ActionGraph, Alphabet, SkeletonGraph, all_done, skeleton_moves
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
    """A lower bound on N from the order of actions and the least moves between poses (``docs/formulation.md``).

    Shortest path over the states (delivered, held, pushed, last pose) where each
    action costs the phases it needs at least: the least number of straight moves from
    the previous pose (or the start) to the action's pose (Eq. 18, exactly:
    :class:`expert.milp.moves.LeastMoves`), at least 1; a push costs 1 more (its stroke)
    unless the previous pose can already be the stroke's start (a push acts from the
    previous phase's base). Poses are boxes of lattice points; taking
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

    def __init__(self, problem: Problem, deadline: Deadline = NEVER, max_edges: int = MAX_EDGES) -> None:
        self.problem, self.max_edges = problem, max_edges
        self.actions = _actions_by_key(problem)
        self.moves = problem_moves(problem)
        self.steps: dict = {}
        self._graph: SkeletonGraph | None = None

    def graph(self, deadline: Deadline = NEVER) -> SkeletonGraph:
        """The skeleton graph of the problem with these steps' costs (built on the first call, then kept).

        Raises :class:`~expert.milp.skeleton_graph.GraphTooLarge` past ``max_edges`` edges.
        """
        if self._graph is None:
            poses = {key: action.poses for key, action in self.actions.items()}
            self._graph = SkeletonGraph.build(self.problem, poses, self.step, deadline, self.max_edges)
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
            found = self.steps[key] = (_step_cost(self.moves, self.problem, where, kind, entry), travel)
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
    reached = np.flatnonzero(arrival[1:] <= n) + 1  # the start (node 0) did no action
    nodes = {column: values[reached] for column, values in graph.columns.items()}
    index = {key: i for i, key in enumerate(keys)}
    key_of = np.array([index.get(key, -1) for key in graph.names.keys], dtype=np.intp)[nodes["last"]]
    first, last = arrival[reached], n - 1 - remaining[reached]
    if last_at_end:  # the last action of a finished state is at N - 1
        first = np.where(graph.finished[reached] & (first <= n - 1), n - 1, first)
    phases = np.arange(n)
    at = ((phases >= np.maximum(first, 1)[:, None]) & (phases <= last[:, None])).astype(np.intp)
    done = _done_before(keys, graph.names, nodes)
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


def _done_before(keys: list[tuple[str, str]], names: Alphabet, nodes: dict[str, np.ndarray]) -> np.ndarray:
    """``[s, j]``: whether action ``keys[j]`` was done before the action that led to skeleton node ``s``.

    ``nodes`` holds the nodes' integer columns (:class:`~expert.milp.skeleton_graph.ActionGraph`'s):
    an object delivered was picked and placed, the one held was picked, a piece pushed was
    pushed; the last action itself is not before.
    """
    done = np.zeros((len(nodes["last"]), len(keys)), dtype=bool)
    for j, (kind, target) in enumerate(keys):
        if kind == "push":
            done[:, j] = nodes["pushed_set"] >> names.pieces.index(target) & 1 == 1
        else:
            i = names.objects.index(target)
            done[:, j] = nodes["delivered_set"] >> i & 1 == 1
            if kind == "pick":
                done[:, j] |= nodes["held"] == i
        done[:, j] &= nodes["last"] != names.keys.index((kind, target))
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


def _step_cost(moves: LeastMoves, problem: Problem, where: IndexBox | None, kind: str, entry: IndexBox) -> int:
    """Phases needed at least from base set ``where`` (None: the start) to the end of an action entered at ``entry``.

    A pick or a place is done from the last of its moves (at least one phase); a push's
    stroke is a phase of its own after the moves to where it starts.
    """
    least = moves.steps(problem, where, entry)
    return least + 1 if kind == "push" else max(1, least)
