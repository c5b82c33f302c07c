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
from dataclasses import dataclass

import numpy as np
from pyscipopt import quicksum

from expert.milp.bounds import PairCosts, _finished, _moves
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
    inf = math.inf
    constant = -DELIVERY_BONUS * (len(problem.deliver) + len(problem.delivered)) * n
    phases = np.arange(n, dtype=float)
    step = pair.step

    # The states, level by level (each action adds one to the count of actions done).
    start = (frozenset(), problem.holding, frozenset(), None, None)
    levels = [[start]]
    edges: dict = {}
    seen = {start}
    while levels[-1]:
        nxt_level = []
        for state in levels[-1]:
            deadline.check()
            delivered, held, pushed, _, where = state
            out = []
            for key, (d, h, p) in _moves(problem, delivered, held, pushed):
                for entry, exit_box in pair.actions[key].poses:
                    q, t = step(where, key[0], entry, exit_box)
                    if q > n - 1:
                        continue
                    succ = (d, h, p, key, exit_box)
                    out.append((succ, q, t))
                    if succ not in seen:
                        seen.add(succ)
                        nxt_level.append(succ)
            edges[state] = out
        levels.append(nxt_level)

    def bonus(state) -> np.ndarray:
        """Eq. 1's ``W1 t`` for arriving at ``state`` at each phase ``t`` (inf where it cannot arrive)."""
        key = state[3]
        if key is None or key[0] != "place":
            return np.zeros(n)
        if last_at_end and _finished(problem, state[0], state[2]):
            out = np.full(n, inf)
            out[n - 1] = DELIVERY_BONUS * (n - 1)
            return out
        return DELIVERY_BONUS * phases

    # Forward: arrive[s][t], the cheapest path to s at exactly t, then slack (prefix minimum) and the bonus.
    forward: dict = {}
    arrive: dict = {start: np.concatenate(([0.0], np.full(n - 1, inf)))}
    for level in levels:
        for state in level:
            deadline.check()
            row = arrive.pop(state, None)
            if row is None:
                forward[state] = np.full(n, inf)
                continue
            row = (np.minimum.accumulate(row) if state[3] is not None else row) + bonus(state)
            forward[state] = row
            if not np.isfinite(row).any():
                continue
            for succ, q, t in edges[state]:
                shifted = np.full(n, inf)
                shifted[q:] = row[: n - q] + t
                if succ in arrive:
                    np.minimum(arrive[succ], shifted, out=arrive[succ])
                else:
                    arrive[succ] = shifted

    # Backward: leave[s][t], the cheapest way to finish from s at t; through[s'][t] = bonus + leave, suffix minimum.
    suffix: dict = {}
    bound: dict = {}
    for level in reversed(levels):
        for state in level:
            deadline.check()
            if _finished(problem, state[0], state[2]):
                leave = np.zeros(n)
            else:
                leave = np.full(n, inf)
                for succ, q, t in edges[state]:
                    later = suffix.get(succ)
                    if later is None:
                        continue
                    shifted = np.full(n, inf)
                    shifted[: n - q] = later[q:] + t
                    np.minimum(leave, shifted, out=leave)
            through = bonus(state) + leave
            suffix[state] = np.minimum.accumulate(through[::-1])[::-1]
            if state[3] is not None:
                total = forward[state] + leave + constant
                slot = (state[3], state[4])
                if slot in bound:
                    np.minimum(bound[slot], total, out=bound[slot])
                else:
                    bound[slot] = total
    return Conditional(n, bound)


def exit_box_of(option) -> IndexBox:
    """Where the base is at the end of ``option``'s phase: its box, or a push's box shifted by the stroke."""
    return option.box.shifted(*option.push.cells) if option.push is not None else option.box


def add_conditional_cuts(milp, conditional: Conditional) -> int:
    """The cuts of the module docstring; options with no bound (no plan does them at that phase) are fixed to 0.

    Returns how many were fixed.
    """
    model, problem = milp.model, milp.problem
    groups: dict[Key, list] = {}
    fixed = 0
    for k, chosen in enumerate(milp.z):
        for o, z in chosen.items():
            option = problem.options[o]
            key = (option.kind, option.target)
            value = conditional.at(key, exit_box_of(option), k)
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
    """Fix to 0 the options whose bound exceeds ``incumbent``, Eq. 1 of a plan SCIP accepted in this model.

    No plan through them beats the one at hand, so the optimum stays in the model. Returns how many.
    """
    fixed = 0
    for k, chosen in enumerate(milp.z):
        for o, z in chosen.items():
            option = milp.problem.options[o]
            value = conditional.at((option.kind, option.target), exit_box_of(option), k)
            if math.isfinite(value) and value > incumbent + 1e-6:
                milp.model.chgVarUb(z, 0.0)
                fixed += 1
    return fixed
