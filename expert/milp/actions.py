"""Pick, place, carry and grasp logic; one object in the hand at a time (the paper's Eq. 4-7).

The paper defines ``theta^{pck}_{i,k} = NOT theta^{gsp}_{i,k-1} AND theta^{gsp}_{i,k}``
(Eq. 4), ``theta^{plc}_{i,k} = NOT theta^{gsp}_{i,k} AND theta^{gsp}_{i,k-1}`` (Eq. 5) and
``theta^{cry} = theta^{gsp} - theta^{pck}`` (Eq. 6). With ``theta^{pck}`` and
``theta^{plc}`` the sums of the pick and place options of object ``i``
(:mod:`expert.milp.postures`) and at most one action per phase, Eq. 4 and 5 together
are exactly the linear balance

    theta^{gsp}_{i,k} = theta^{gsp}_{i,k-1} + theta^{pck}_{i,k} - theta^{plc}_{i,k},

with ``theta^{gsp}`` in [0, 1]: a pick needs an empty hand for ``i`` before and a
held ``i`` after; a place the converse. Eq. 6 (carrying) is then an expression,
``gsp - pck``, used by nobody: a carried object simply follows the hand (Eq. 8).

Eq. 7 (at most one object held): ``sum_i theta^{gsp}_{i,k} <= 1``. A push may be made
with an empty hand or holding an object (the paper pushes while carrying the object it
places, ``docs/design.md``), so pushes do not enter it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pyscipopt import quicksum

if TYPE_CHECKING:
    from expert.milp.variables import Milp


def add_action_constraints(milp: Milp) -> None:
    """Eq. 4-7, plus one arm action per phase."""
    model = milp.model
    for k in range(1, milp.n_phases):
        if len(milp.z[k]) > 1:
            model.addCons(quicksum(milp.z[k].values()) <= 1, name=f"one_action_{k}")
        for object_id in milp.problem.deliver:
            picks = milp.action_sum("pick", object_id, k)
            places = milp.action_sum("place", object_id, k)
            balance = (
                milp.gsp[object_id][k - 1] + (picks if picks is not None else 0) - (places if places is not None else 0)
            )
            model.addCons(milp.gsp[object_id][k] == balance, name=f"eq4_6_grasp_{object_id}_{k}")
        held = [milp.gsp[i][k] for i in milp.problem.deliver]
        if len(held) > 1:
            model.addCons(quicksum(held) <= 1, name=f"eq7_one_in_hand_{k}")
