"""The task cost's lower bound given where and when an action is done: the skeleton search run both ways.

:func:`expert.milp.bounds.min_objective` bounds the task cost (the MILP's objective) over every plan: the cheapest path
of a relaxation whose states are (delivered, held, pushed, last action, its exit pose
box) and whose steps cost the least phases and the least travel between pose boxes, plus
``W1 t`` at each place done at phase ``t``. Every plan maps onto a path of that graph
with its actual phases (a step may take more phases than the least: "slack"), whose
cost is at most the plan's task cost.

Here the same graph is searched forwards from the start and backwards from the finished
states, with slack, phase by phase: ``F[s][t]`` is the cheapest path from the start that
reaches state ``s`` at phase ``t``, ``B[s][t]`` the cheapest way to finish from there, so
``F + B`` (plus the task cost's constant) bounds every plan that passes through ``s`` at ``t``. The
least of it over the states of one action and pose box gives :class:`Conditional`:
``bound[(kind, target), exit box][t]``, a lower bound on the task cost of every plan that does
the action from a pose of that box at phase ``t`` (``inf``: no plan does).

The MILP uses it twice (:func:`add_conditional_cuts`, :func:`fix_above`), both exact:

- every action is done exactly once, so for each action ``a``
  ``cost >= sum_{k, o in a} bound(o, k) z[k][o]`` is valid; the LP then pays for an
  action done at a costly phase or pose, in every node of the search (the single bound
  ``cost >= min_objective`` stays at the root's value);
- with a known plan of task cost ``U`` in the model (the warm start), ``z[k][o] = 0`` where
  ``bound(o, k) > U``: no plan through it is better than the one at hand.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
from pyscipopt import quicksum

from expert.milp.bounds import PairCosts
from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import IndexBox
from expert.milp.problem import Problem
from expert.milp.skeleton_graph import SkeletonGraph, run_starts
from fetchcarry_env.kinematics import WAIT_COST

Key = tuple[str, str]


@dataclass(frozen=True)
class Conditional:
    """Lower bounds on the task cost per action, exit pose box and phase (:func:`conditional_bounds`)."""

    n_phases: int
    bound: dict[tuple[Key, IndexBox], np.ndarray]  # per phase 0..N-1; inf where no plan does it

    @property
    def least(self) -> float:
        """The least bound over every action, pose box and phase: :func:`expert.milp.bounds.min_objective`."""
        return min((float(np.min(row)) for row in self.bound.values()), default=math.inf)

    def order(self, kind: str) -> list[str]:
        """Targets of the actions of ``kind``, by the first phase at which one lies on a cheapest path.

        A cheapest path of the relaxation is the schedule :func:`expert.milp.bounds.cheapest_schedule`
        finds; where several tie, an action takes its earliest phase over them. Actions on no
        cheapest path are left out.
        """
        least = self.least
        first: dict[str, int] = {}
        for (key, _), row in self.bound.items():
            if key[0] != kind:
                continue
            hits = np.flatnonzero(row <= least + 1e-6)
            if hits.size:
                first[key[1]] = min(first.get(key[1], self.n_phases), int(hits[0]))
        return sorted(first, key=lambda target: (first[target], target))

    def at(self, key: Key, exit_box: IndexBox, k: int) -> float:
        row = self.bound.get((key, exit_box))
        return math.inf if row is None else float(row[k])


def conditional_bounds(
    problem: Problem,
    n_phases: int,
    pair: PairCosts,
    deadline: Deadline = NEVER,
    last_at_end: bool = False,
    order: Sequence[str] | None = None,
) -> Conditional:
    """The bounds of the module docstring for plans with ``n_phases`` phases, on ``pair``'s skeleton graph.

    ``last_at_end``: every plan's last place is at phase ``N - 1`` (``N - 1`` phases admit
    no plan), as in :func:`expert.milp.bounds.min_objective`. ``order``: of the plans that pick
    the objects in that order only (:meth:`expert.milp.skeleton_graph.SkeletonGraph.in_order`).
    """
    n = n_phases
    constant = -WAIT_COST * len(problem.deliver)  # the task cost counts W1 (t - 1) for a delivery at phase t
    graph = pair.graph(deadline).within(n)
    if order is not None:
        graph = graph.in_order(order, problem.deliver)
    slots, rows = np.unique(graph.slot[1:], return_inverse=True)  # the start (state 0) did no action
    band = Band.of(graph, n)
    least = np.full((len(slots), n), math.inf)
    if band is not None:
        bonus = band.bonus(last_at_end)
        total = _forward(band.graph, band.width, bonus, deadline) + _leave(band.graph, band.width, bonus, deadline)
        least = band.least_by_phase(total[:, 1:] + constant, band.arrival[1:], rows, len(slots))
    return Conditional(n, {graph.slots[slot]: row for slot, row in zip(slots, least, strict=True)})


def least_by_last_phase(problem: Problem, n_phases: int, pair: PairCosts, deadline: Deadline = NEVER) -> np.ndarray:
    """``[t]`` for ``t < n_phases``: a lower bound on the task cost of every plan whose last place is at phase ``t``
    (``inf`` where none can be), from one forward search of the skeleton graph.

    The forward table's value at a finished state and phase ``t`` is the cheapest path of the
    relaxation that does its last place at ``t`` (slack allowed before), with ``W1 t`` counted
    at every place: every such plan maps onto one of them at no more cost (the module docstring).
    """
    graph = pair.graph(deadline).within(n_phases)
    band = Band.of(graph, n_phases)
    last = graph.finished & graph.placed
    if band is None or not last.any():
        return np.full(n_phases, math.inf)
    forward = _forward(band.graph, band.width, band.bonus(last_at_end=False), deadline)
    least = band.least_by_phase(forward[:, last], band.arrival[last], np.zeros(int(last.sum()), dtype=np.intp), 1)
    return least[0] - WAIT_COST * len(problem.deliver)


@dataclass(frozen=True)
class Band:
    """A graph's searches for ``n_phases`` on the phases where a state can lie on a plan, its band.

    A state ``s`` is reached at phase ``arrival[s]`` at the earliest (the least phases from
    the start) and left, on a plan, by ``N - 1 - remaining[s]``; since ``arrival + remaining``
    is at least ``A``, the least phases of a finished state, every such phase is
    ``arrival[s] + j`` with ``0 <= j < width = N - A``. Both tables keep those ``width``
    columns only (``inf`` beyond ``N - 1``), and an edge ``s -> d`` of ``q`` phases links
    column ``j`` of ``s`` to column ``j + k`` of ``d``, its shift ``k = arrival[s] + q -
    arrival[d] >= 0``: the searches of the dense tables run unchanged with ``k`` for ``q`` and
    ``width`` for ``N``, and an edge with ``k >= width`` is left out (it reaches no column).
    The values are the dense tables' on the band, bit for bit (the same sums in the same
    order), and ``inf`` off it in both.
    """

    graph: SkeletonGraph  # the edges of a shift below ``width``, ``q`` their shift
    arrival: np.ndarray  # per state, the least phases from the start (inf: unreachable within N)
    width: int
    n_phases: int

    @classmethod
    def of(cls, graph: SkeletonGraph, n_phases: int) -> Band | None:
        """The band of ``graph`` (its edges all within ``n_phases``); None when no finished state is reached."""
        arrival = graph.least_from_start(graph.q.astype(float))
        finished = arrival[graph.finished]
        if not finished.size or not finished.min() <= n_phases - 1:
            return None
        width = n_phases - int(finished.min())
        with np.errstate(invalid="ignore"):  # inf - inf from an unreachable state: nan, and left out
            shift = arrival[graph.src] + graph.q - arrival[graph.dst]
            keep = shift < width
        banded = dataclasses.replace(graph.keeping(keep), q=shift[keep].astype(np.intp))
        return cls(banded, arrival, width, n_phases)

    def bonus(self, last_at_end: bool) -> np.ndarray:
        """``[j, s]``: the W1 t of arriving at state s at phase ``t = arrival[s] + j``; inf past ``N - 1`` and, with
        ``last_at_end``, for a last place before it."""
        n, graph = self.n_phases, self.graph
        phase = self.arrival[None, :] + np.arange(self.width)[:, None]
        bonus = np.where(graph.placed, WAIT_COST * phase, 0.0)
        if last_at_end:
            last = graph.placed & graph.finished
            bonus = np.where(last & (phase < n - 1), math.inf, bonus)
        return np.where(phase <= n - 1, bonus, math.inf)

    def least_by_phase(self, values: np.ndarray, arrival: np.ndarray, rows: np.ndarray, count: int) -> np.ndarray:
        """``[r, t]``: the least of ``values[j, s]`` over the states ``s`` of row ``r`` (``rows[s]``) at phase
        ``t = arrival[s] + j``, of ``count`` rows and ``n_phases`` phases; inf where none."""
        n = self.n_phases
        least = np.full(count * n, math.inf)
        for j in range(self.width):
            phase = arrival + j
            on = phase <= n - 1
            np.minimum.at(least, rows[on] * n + phase[on].astype(np.intp), values[j, on])
        return least.reshape(count, n)


# The searches below keep their tables phase by phase, one row per phase and one column per
# state: a minimum over the edges into (or out of) a state is then one reduceat along rows,
# several times faster than along columns.


def _forward(graph: SkeletonGraph, n: int, bonus: np.ndarray, deadline: Deadline) -> np.ndarray:
    """``[t, s]``: the cheapest path to s at phase t, with slack (a prefix minimum over t), bonus included."""
    phases = np.arange(n)[:, None]
    forward = np.full((2 * n, graph.state_count), math.inf)  # upper half: inf, so that a shift by q reads inf
    forward[n, 0] = 0.0
    for e0, e1 in pairwise(graph.edge_starts):
        if e0 == e1:
            continue
        deadline.check()
        order = graph.by_destination[e0:e1]
        reached, firsts = graph.destinations(e0, e1)
        values = forward[n - graph.q[order] + phases, graph.src[order]] + graph.t[order]
        arrive = np.minimum.reduceat(values, firsts, axis=1)
        forward[n:, reached] = np.minimum.accumulate(arrive, axis=0) + bonus[:, reached]
    return forward[n:]


def _leave(graph: SkeletonGraph, n: int, bonus: np.ndarray, deadline: Deadline) -> np.ndarray:
    """``[t, s]``: the cheapest way to finish from s at phase t; through = bonus + leave, suffix minimum over t."""
    phases = np.arange(n)[:, None]
    src_a, dst_a, q_a, t_a = graph.src, graph.dst, graph.q, graph.t
    level_starts, edge_starts = graph.level_starts, graph.edge_starts
    leave = np.full((n, graph.state_count), math.inf)
    leave[:, graph.finished] = 0.0
    suffix = np.full((2 * n, graph.state_count), math.inf)  # lower half: inf (no phase beyond N - 1)
    for level in range(len(level_starts) - 2, -1, -1):
        deadline.check()
        e0, e1 = edge_starts[level], edge_starts[level + 1] if level + 1 < len(edge_starts) else len(src_a)
        if e1 > e0:
            sources = src_a[e0:e1]
            values = suffix[q_a[e0:e1] + phases, dst_a[e0:e1]] + t_a[e0:e1]
            firsts = run_starts(sources)
            leave[:, sources[firsts]] = np.minimum.reduceat(values, firsts, axis=1)
        states = slice(level_starts[level], level_starts[level + 1])
        suffix[:n, states] = np.minimum.accumulate((bonus[:, states] + leave[:, states])[::-1], axis=0)[::-1]
    return leave


def exit_box_of(option) -> IndexBox:
    """Where the base is at the end of ``option``'s phase: its box, or a push's box shifted by the stroke."""
    return option.box.shifted(*option.push.cells) if option.push is not None else option.box


def _bounded_options(milp, conditional: Conditional) -> Iterator[tuple[Key, float, object]]:
    """``(action, bound, z)`` for every option binary ``z[k][o]`` of the model: its action and its bound at ``k``."""
    for k, chosen in enumerate(milp.z):
        for o, z in chosen.items():
            option = milp.problem.options[o]
            key = (option.kind, option.target)
            yield key, conditional.at(key, exit_box_of(option), k), z


def add_conditional_cuts(milp, conditional: Conditional) -> int:
    """The cuts of the module docstring; options with no bound (no plan does them at that phase) are fixed to 0.

    Returns how many were fixed.
    """
    model = milp.model
    groups: dict[Key, list] = {}
    fixed = 0
    for key, value, z in _bounded_options(milp, conditional):
        if not math.isfinite(value):
            model.chgVarUb(z, 0.0)
            fixed += 1
            continue
        groups.setdefault(key, []).append((value, z))
    for key, terms in groups.items():
        floor = min(value for value, _ in terms)
        if all(value <= floor + 1e-9 for value, _ in terms):
            continue
        expr = quicksum((value - floor) * z for value, z in terms if value > floor + 1e-9)
        model.addCons(milp.objective >= floor - 1e-6 + expr, name=f"conditional_{key[0]}_{key[1]}")
    return fixed


def fix_unreached(milp, conditional: Conditional) -> list:
    """Fix to 0 the options that no plan of ``conditional`` does (bound ``inf``); the ones not fixed before.

    For the bounds of a restricted model (``conditional_bounds(..., order=...)``): the
    caller frees them again (``chgVarUb(z, 1)``) when the restriction is lifted.
    """
    fixed = []
    for _, value, z in _bounded_options(milp, conditional):
        if not math.isfinite(value) and z.getUbOriginal() > 0.5:
            milp.model.chgVarUb(z, 0.0)
            fixed.append(z)
    return fixed


def fix_above(milp, conditional: Conditional, incumbent: float, keep_ties: bool = True) -> int:
    """Fix to 0 the options whose bound exceeds ``incumbent``, the task cost of a plan checked feasible in this model.

    The caller passes the task cost of a warm start only when :func:`expert.milp.warm.add_warm_start`
    returned True (the plan passed ``checkSol``); an unchecked plan could cut the optimum off.
    With ``keep_ties=False`` (a model asked only for plans costing less than ``incumbent``,
    the best plan's cost) the options whose bound equals it are fixed too.

    No plan through them beats the one at hand, so the optimum stays in the model. Returns how many.
    """
    limit = incumbent + 1e-6 if keep_ties else incumbent - 1e-6
    fixed = 0
    for _, value, z in _bounded_options(milp, conditional):
        if math.isfinite(value) and value > limit:
            milp.model.chgVarUb(z, 0.0)
            fixed += 1
    return fixed
