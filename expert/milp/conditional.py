"""Eq. 1's lower bound given where and when an action is done: the skeleton search run both ways.

:func:`expert.milp.bounds.min_objective` bounds Eq. 1 over every plan: the cheapest path
of a relaxation whose states are (delivered, held, pushed, last action, its exit pose
box) and whose steps cost the least phases and the least travel between pose boxes, plus
``W1 t`` at each place done at phase ``t``. Every plan maps onto a path of that graph
with its actual phases (a step may take more phases than the least: "slack"), whose
cost is at most the plan's Eq. 1.

Here the same graph is searched forwards from the start and backwards from the finished
states, with slack, phase by phase: ``F[s][t]`` is the cheapest path from the start that
reaches state ``s`` at phase ``t``, ``B[s][t]`` the cheapest way to finish from there, so
``F + B`` (plus Eq. 1's constant) bounds every plan that passes through ``s`` at ``t``. The
least of it over the states of one action and pose box gives :class:`Conditional`:
``bound[(kind, target), exit box][t]``, a lower bound on Eq. 1 of every plan that does
the action from a pose of that box at phase ``t`` (``inf``: no plan does).

The MILP uses it twice (:func:`add_conditional_cuts`, :func:`fix_above`), both exact:

- every action is done exactly once, so for each action ``a``
  ``Eq. 1 >= sum_{k, o in a} bound(o, k) z[k][o]`` is valid; the LP then pays for an
  action done at a costly phase or pose, in every node of the search (the single bound
  ``Eq. 1 >= min_objective`` stays at the root's value);
- with a known plan of Eq. 1 ``U`` in the model (the warm start), ``z[k][o] = 0`` where
  ``bound(o, k) > U``: no plan through it is better than the one at hand.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from pyscipopt import quicksum

from expert.milp.bounds import PairCosts, all_done, skeleton_moves
from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import IndexBox
from expert.milp.problem import Problem
from fetchcarry_env.kinematics import DELIVERY_BONUS

Key = tuple[str, str]


@dataclass(frozen=True)
class Conditional:
    """Lower bounds on Eq. 1 per action, exit pose box and phase (:func:`conditional_bounds`)."""

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
) -> Conditional:
    """The bounds of the module docstring for plans with ``n_phases`` phases.

    ``last_at_end``: every plan's last place is at phase ``N - 1`` (``N - 1`` phases admit
    no plan), as in :func:`expert.milp.bounds.min_objective`.
    """
    n = n_phases
    constant = -DELIVERY_BONUS * (len(problem.deliver) + len(problem.delivered)) * n
    graph = _Graph.search(problem, n, pair, deadline)
    bonus, finished = _arrival_bonus(problem, graph.states, n, last_at_end)
    total = graph.forward(bonus, deadline) + graph.leave(bonus, finished, deadline) + constant
    bound: dict = {}
    for sid in range(1, len(graph.states)):
        slot = (graph.states[sid][3], graph.states[sid][4])
        if slot in bound:
            np.minimum(bound[slot], total[sid], out=bound[slot])
        else:
            bound[slot] = total[sid].copy()
    return Conditional(n, bound)


@dataclass(frozen=True)
class _Graph:
    """The skeleton's states with their last action and exit box, level by level, and its edges.

    Each action adds one to the actions done, so every edge goes from one level to the
    next, and a level's edges are listed by their source. ``src[e] -> dst[e]`` costs at
    least ``q[e]`` phases and ``t[e]`` metres of travel.
    """

    n_phases: int
    states: list[tuple]  # (delivered, held, pushed, last action, its exit box), ids in order of discovery
    level_starts: list[int]  # states of level L: level_starts[L] .. level_starts[L + 1] - 1
    edge_starts: list[int]  # edges out of level L: edge_starts[L] .. edge_starts[L + 1] - 1
    src: np.ndarray
    dst: np.ndarray
    q: np.ndarray
    t: np.ndarray

    @classmethod
    def search(cls, problem: Problem, n: int, pair: PairCosts, deadline: Deadline) -> _Graph:
        """Every state reachable from the start with steps of at most ``n - 1`` phases each."""
        start = (frozenset(), problem.holding, frozenset(), None, None)
        states = [start]
        # A state is found by its exit box's number (hashed in C; a box's hash runs Python),
        # and the steps of an action from a box, which depend on nothing else, are listed once.
        boxes: list[IndexBox | None] = [None]
        numbers: dict[IndexBox | None, int] = {None: 0}
        exits = [0]  # per state, its exit box's number
        ids = {(start[0], start[1], start[2], None, 0): 0}
        steps: dict = {}  # (exit number, action) -> [(phases, travel, next exit number)], phases <= n - 1

        def number(box: IndexBox) -> int:
            if box not in numbers:
                numbers[box] = len(boxes)
                boxes.append(box)
            return numbers[box]

        level_starts = [0, 1]
        edge_starts = [0]
        src: list[int] = []
        dst: list[int] = []
        qs: list[int] = []
        ts: list[float] = []
        while level_starts[-1] > level_starts[-2]:
            for sid in range(level_starts[-2], level_starts[-1]):
                deadline.check()
                delivered, held, pushed, _, where = states[sid]
                for key, (d, h, p) in skeleton_moves(problem, delivered, held, pushed):
                    found = steps.get((exits[sid], key))
                    if found is None:
                        found = steps[exits[sid], key] = []
                        for entry, exit_box in pair.actions[key].poses:
                            q, t = pair.step(where, key[0], entry, exit_box)
                            if q <= n - 1:
                                found.append((q, t, number(exit_box)))
                    for q, t, x in found:
                        j = ids.get((d, h, p, key, x))
                        if j is None:
                            j = ids[d, h, p, key, x] = len(states)
                            states.append((d, h, p, key, boxes[x]))
                            exits.append(x)
                        src.append(sid)
                        dst.append(j)
                        qs.append(q)
                        ts.append(t)
            edge_starts.append(len(src))
            level_starts.append(len(states))
        return cls(
            n,
            states,
            level_starts,
            edge_starts,
            np.asarray(src, dtype=np.intp),
            np.asarray(dst, dtype=np.intp),
            np.asarray(qs, dtype=np.intp),
            np.asarray(ts, dtype=float),
        )

    def forward(self, bonus: np.ndarray, deadline: Deadline) -> np.ndarray:
        """The cheapest path to s at phase t, with slack (a prefix minimum over t), bonus included."""
        n, cols = self.n_phases, np.arange(self.n_phases)
        src_a, dst_a, q_a, t_a = self.src, self.dst, self.q, self.t
        forward = np.full((len(self.states), 2 * n), math.inf)  # left half: inf, so that a shift by q reads inf
        forward[0, n] = 0.0
        for level in range(len(self.edge_starts) - 1):
            e0, e1 = self.edge_starts[level], self.edge_starts[level + 1]
            if e0 == e1:
                continue
            deadline.check()
            order = e0 + np.argsort(dst_a[e0:e1], kind="stable")
            targets = dst_a[order]
            values = forward[src_a[order][:, None], (n - q_a[order])[:, None] + cols] + t_a[order][:, None]
            firsts = np.flatnonzero(np.r_[True, targets[1:] != targets[:-1]])
            arrive = np.minimum.reduceat(values, firsts, axis=0)
            reached = targets[firsts]
            forward[reached, n:] = np.minimum.accumulate(arrive, axis=1) + bonus[reached]
        return forward[:, n:]

    def leave(self, bonus: np.ndarray, finished: np.ndarray, deadline: Deadline) -> np.ndarray:
        """The cheapest way to finish from s at phase t; through = bonus + leave, suffix minimum over t."""
        n, cols = self.n_phases, np.arange(self.n_phases)
        src_a, dst_a, q_a, t_a = self.src, self.dst, self.q, self.t
        level_starts, edge_starts = self.level_starts, self.edge_starts
        leave = np.full((len(self.states), n), math.inf)
        leave[finished] = 0.0
        suffix = np.full((len(self.states), 2 * n), math.inf)  # right half: inf (no phase beyond N - 1)
        for level in range(len(level_starts) - 2, -1, -1):
            deadline.check()
            e0, e1 = edge_starts[level], edge_starts[level + 1] if level + 1 < len(edge_starts) else len(src_a)
            if e1 > e0:
                sources = src_a[e0:e1]
                values = suffix[dst_a[e0:e1][:, None], q_a[e0:e1][:, None] + cols] + t_a[e0:e1][:, None]
                firsts = np.flatnonzero(np.r_[True, sources[1:] != sources[:-1]])
                leave[sources[firsts]] = np.minimum.reduceat(values, firsts, axis=0)
            rows = slice(level_starts[level], level_starts[level + 1])
            suffix[rows, :n] = np.minimum.accumulate((bonus[rows] + leave[rows])[:, ::-1], axis=1)[:, ::-1]
        return leave


def _arrival_bonus(problem: Problem, states: list[tuple], n: int, last_at_end: bool) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 1's W1 t for arriving at each state at phase t (inf where a last place cannot be); which states finish."""
    cols = np.arange(n)
    bonus = np.zeros((len(states), n))
    finished = np.zeros(len(states), dtype=bool)
    for sid, (delivered, _, pushed, key, _) in enumerate(states):
        finished[sid] = all_done(problem, delivered, pushed)
        if key is not None and key[0] == "place":
            if last_at_end and finished[sid]:
                bonus[sid, : n - 1] = math.inf
                bonus[sid, n - 1] = DELIVERY_BONUS * (n - 1)
            else:
                bonus[sid] = DELIVERY_BONUS * cols
    return bonus, finished


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


def fix_above(milp, conditional: Conditional, incumbent: float) -> int:
    """Fix to 0 the options whose bound exceeds ``incumbent``, Eq. 1 of a plan checked feasible in this model.

    The caller passes the Eq. 1 of a warm start only when :func:`expert.milp.warm.add_warm_start`
    returned True (the plan passed ``checkSol``); an unchecked plan could cut the optimum off.

    No plan through them beats the one at hand, so the optimum stays in the model. Returns how many.
    """
    fixed = 0
    for _, value, z in _bounded_options(milp, conditional):
        if math.isfinite(value) and value > incumbent + 1e-6:
            milp.model.chgVarUb(z, 0.0)
            fixed += 1
    return fixed
