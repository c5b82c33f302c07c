"""Action windows given the order of two actions: valid inequalities from :func:`expert.milp.bounds.action_windows`.

The windows say at which phases an action ``a`` can happen at all; they are a union
over the orders of actions. Given whether another action ``b`` was done before ``a``,
the phases of ``a`` are fewer: a pick that comes after a push can only be late, one
that comes before it only early. With ``A_k`` the options of ``a`` at phase ``k`` and
``done_b[k-1]`` whether ``b`` was done by phase ``k - 1`` (a sum of the model's own
continuous state variables, 0 or 1 in every solution):

- ``A_k <= 1 - done_b[k-1]`` when no plan does ``a`` at ``k`` after ``b``;
- ``A_k <= done_b[k-1]`` when no plan does ``a`` at ``k`` before ``b``.

Every plan of the model satisfies both (the windows are exact relaxation bounds), so
the optimum is unchanged.

:func:`add_pick_order` is not a valid inequality but a restriction, for a first plan:
the objects delivered in a given order (``docs/benchmarks/planner.md``, "A first plan in
the relaxation's order").
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import TYPE_CHECKING

from expert.milp.deadline import NEVER, Deadline
from expert.milp.variables import Expr, Milp

if TYPE_CHECKING:
    from expert.milp.bounds import Windows


def add_order_windows(milp: Milp, windows: Windows, deadline: Deadline = NEVER) -> None:
    """``A_k <= done_b[k-1]`` or ``<= 1 - done_b[k-1]`` where the windows given ``b`` exclude phase ``k``."""
    model = milp.model
    keys = sorted(windows.phases)
    for a in keys:
        deadline.check()
        for b in keys:
            if b == a or (a[0] == "place" and b == ("pick", a[1])):  # a place follows its pick by Eq. 4-6 already
                continue
            after = windows.given.get((a, b, True), frozenset())
            before = windows.given.get((a, b, False), frozenset())
            for k in sorted(windows.phases[a]):
                if k in after and k in before:
                    continue
                now = milp.action_sum(a[0], a[1], k)
                done = _done_by(milp, b, k - 1)
                if now is None or done is None:
                    continue
                tag = f"{a[0]}_{a[1]}_{b[0]}_{b[1]}_{k}"
                if k not in after:
                    model.addCons(now <= 1 - done, name=f"order_not_after_{tag}")
                if k not in before:
                    model.addCons(now <= done, name=f"order_not_before_{tag}")


def add_pick_order(milp: Milp, order: Sequence[str]) -> list:
    """Only plans that pick the objects in ``order``: each pick once the object before it is placed.

    ``pick(b)`` at phase ``k`` only if ``a``, the object before ``b`` in ``order``, is
    delivered by phase ``k - 1`` (``delta[a][k-1]``). Objects of ``order`` the model does
    not deliver are skipped. The optimum of the restricted model is a plan of the whole
    one (the best with that order), not its optimum. Returns the constraints added, for
    ``delCons`` once SCIP is back in its problem stage.
    """
    chain = [target for target in order if target in milp.delta]
    added = []
    for before, after in itertools.pairwise(chain):
        for k in range(1, milp.n_phases):
            now = milp.action_sum("pick", after, k)
            if now is not None:
                name = f"pick_order_{before}_{after}_{k}"
                added.append(milp.model.addCons(now <= milp.delta[before][k - 1], name=name))
    return added


def _done_by(milp: Milp, action: tuple[str, str], k: int) -> Expr | None:
    """Whether ``action`` was done by the end of phase ``k`` (an expression in the model's state variables)."""
    kind, target = action
    if kind == "push":
        return milp.pushed[target][k] if target in milp.pushed else None
    if target not in milp.delta:
        return None
    if kind == "place":
        return milp.delta[target][k]
    return milp.gsp[target][k] + milp.delta[target][k]  # picked by then: held, or placed
