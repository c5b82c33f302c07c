"""Valid inequalities for a model whose number of phases is the fewest that can admit a plan.

The planner builds the model with ``N`` phases only when ``N - 1`` phases are proven to
admit no plan (``N`` is a proven lower bound, or the ``N - 1`` model was infeasible).
Every plan with ``N`` phases then has:

- **its last phase a place** (``sum_o z[N-1][o] = 1`` over the place options): a plan
  whose last phase only moves, or does nothing, is still a plan without it (every
  object is delivered and every push made by phase ``N - 2``), with ``N - 1`` phases.
  A push cannot be last (it comes before a place, :mod:`expert.milp.push`) and a pick
  neither (a picked object is placed later).
- **no idle phase** (no action and no move): dropping it leaves a valid plan with
  ``N - 1`` phases (the bases before and after it are the same point, so every move
  and every push stroke is unchanged). With integer lattice bases a phase that moves
  moves by at least one lattice step, so ``m^x_k + m^y_k + sum_o z[k][o] >= 1`` (from
  phase 2 when the start is off the lattice: phase 1 may then move by less than a step).

Neither cuts off a plan of the model, so the optimum is unchanged; they remove the
LP's fractional idle phases and the branching over where the slack phases go. Not
used with ``extra_phases`` (idle phases are how shorter plans live in that model).
"""

from __future__ import annotations

from pyscipopt import quicksum

from expert.milp.variables import Milp


def add_fewest_phase_cuts(milp: Milp) -> None:
    """The last phase places; with integer bases, no phase is idle."""
    model, n, problem = milp.model, milp.n_phases, milp.problem
    places = [z for o, z in milp.z[n - 1].items() if problem.options[o].kind == "place"]
    model.addCons(quicksum(places) == 1, name="fewest_last_is_place")
    if not problem.grid.integral:
        return
    first = 1 if problem.start_index is not None else 2  # from an off-lattice start, phase 1 may move < 1 step
    for k in range(first, n - 1):
        acts = quicksum(milp.z[k].values()) if milp.z[k] else 0
        model.addCons(milp.mx[k] + milp.my[k] + acts >= 1, name=f"fewest_not_idle_{k}")
