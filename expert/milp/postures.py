"""Heading x posture selection at picks, places and pushes (the paper's Eq. 14-17).

One binary ``z_{o,k}`` per pose option (:mod:`expert.milp.options`) and phase is the
product ``theta_k^{h,alpha} * theta_{i,k}^{pck|plc}`` of the paper, disaggregated
(tighter than linearising the product):

- Eq. 14, 16: at most one option per phase (together with one action per phase in
  :mod:`expert.milp.actions`);
- Eq. 15, 17: ``theta_k^{h,alpha} = sum`` of the options with that heading and posture,
  and ``theta_{i,k}^{pck} = sum`` of the pick options of ``i`` (expressions, no variables);
- the reach constraint (:func:`add_posture_constraints`): the acting base lies in the
  chosen option's box, written as one aggregated big-M per bound and phase (valid
  because at most one option is on).
"""

from __future__ import annotations

from pyscipopt import quicksum

from expert.milp.variables import Milp


def add_posture_constraints(milp: Milp) -> None:
    """Eq. 14-17 and the reach boxes: the acting base lies in the box of the option chosen."""
    problem, model, grid = milp.problem, milp.model, milp.problem.grid
    for k in range(1, milp.n_phases):
        # Picks and places act from base_k; pushes from base_{k-1} (the stroke's start).
        for acting, group in ((k, milp.arm_options_at(k)), (k - 1, milp.push_options_at(k))):
            if not group or acting == 0:
                continue
            for axis, coords in ((0, milp.u), (1, milp.v)):
                var_lo, var_hi = grid.var_bounds(axis)
                lower = quicksum((grid.lower(problem.options[o].box.lo(axis)) - var_lo) * z for o, z in group)
                upper = quicksum((var_hi - grid.upper(problem.options[o].box.hi(axis))) * z for o, z in group)
                model.addCons(coords[acting] >= var_lo + lower, name=f"reach_lo_{axis}_{k}_{acting}")
                model.addCons(coords[acting] <= var_hi - upper, name=f"reach_hi_{axis}_{k}_{acting}")
