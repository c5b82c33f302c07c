"""The objective and the motion variables (the paper's Eq. 1-3).

The objective is the task cost: the paper's Eq. 1, ``min -W1 sum_i sum_k delta_{i,k} + sum_k
(m^x_k + m^y_k) + W2 sum_k m^xy_k``, counted from the objects' waiting instead of their
deliveries: ``W1 sum_{i, k >= 1} (1 - delta_{i,k}) + travel``, which differs from Eq. 1 by a
constant of the model (``W1 * objects * phases``, phase 0 included), so the optimum is the
same plan, and the MILP's value is the task cost of the decoded plan
(:func:`expert.plans.task_cost`), for plans of fewer phases followed by idle ones too.
``W1 = WAIT_COST`` and ``W2 = DIAGONAL_WEIGHT`` (``fetchcarry_env.kinematics``).
Eq. 2: ``-m^x_k <= x_k - x_{k-1} <= m^x_k`` (and ``y``). Eq. 3: ``-m^xy_k <= m^x_k - m^y_k <= m^xy_k``.

Distances are kept in lattice-index units and scaled by the resolution in the
objective, so the objective is in metres. Objects already at their goal cost nothing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pyscipopt import quicksum

from fetchcarry_env.kinematics import DIAGONAL_WEIGHT, WAIT_COST

if TYPE_CHECKING:
    from expert.milp.variables import Milp


def add_motion_constraints(milp: Milp) -> None:
    """Eq. 2-3 for every move ``k-1 -> k``."""
    model = milp.model
    for k in range(1, milp.n_phases):
        for coords, moved, axis in ((milp.u, milp.mx, "x"), (milp.v, milp.my, "y")):
            model.addCons(moved[k] >= coords[k] - coords[k - 1], name=f"eq2_{axis}_pos_{k}")
            model.addCons(moved[k] >= coords[k - 1] - coords[k], name=f"eq2_{axis}_neg_{k}")
        model.addCons(milp.mxy[k] >= milp.mx[k] - milp.my[k], name=f"eq3_pos_{k}")
        model.addCons(milp.mxy[k] >= milp.my[k] - milp.mx[k], name=f"eq3_neg_{k}")


def set_objective(milp: Milp, lower_bound: float | None = None) -> None:
    """The task cost (Eq. 1 counted over the whole task), with the valid inequalities ``travel >= min_travel``
    and, if given, ``task cost >= lower_bound``."""
    resolution = milp.problem.grid.resolution
    deliver = milp.problem.deliver
    delivered = quicksum(milp.delta[i][k] for i in deliver for k in range(1, milp.n_phases))
    travel = quicksum(milp.mx[k] + milp.my[k] + DIAGONAL_WEIGHT * milp.mxy[k] for k in range(1, milp.n_phases))
    if milp.problem.min_travel > 0:
        milp.model.addCons(resolution * travel >= milp.problem.min_travel - 1e-6, name="travel_lower_bound")
    waiting = len(deliver) * (milp.n_phases - 1) - delivered  # object-phases after the start not at the goal
    objective = resolution * travel + WAIT_COST * waiting
    if lower_bound is not None and lower_bound > -1e9:
        milp.model.addCons(objective >= lower_bound - 1e-6, name="objective_lower_bound")
    milp.objective = objective
    milp.model.setObjective(objective, sense="minimize")
