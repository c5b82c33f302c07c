"""Push-aside constraints (the paper's IV-E, Eq. 20-26), on the preprocessing of :mod:`expert.milp.strokes`.

With ``z`` the push options chosen at phase k:

- Eq. 20, 25, 26 (stroke of length B, never diagonal): the base moves by exactly the
  option's stroke vector in the push phase: ``u_k - u_{k-1} = sum_o di_o z_{o,k}``
  (and ``v``) whenever a push is chosen, by a big-M pair; ``m^x_k >= sum_o |di_o| z_{o,k}``
  (and ``m^y``) states the paper's ``m^x + m^y = B`` on the cost side.
- Eq. 21-24 (no push towards a neighbour): the blocked directions have no option at
  all, which is what Eq. 21-24 achieve by forcing the motion towards them to zero.
- Each covering piece is pushed exactly once, before the place of each object whose
  goal it covers.

The paper pushes in the placing phase of the object being delivered (``theta^plc_{i,k}
u_i``): the robot arrives holding the object, strokes and places. Here a push is its
own phase (one env action is one phase), with an empty hand or holding any object;
the paper's pattern is the push while holding ``i`` followed by the place of ``i`` at
the stroke's end. The MILP chooses between the two (``docs/formulation.md``).
Eq. 20's product ``theta^plc * u_i`` is linear since ``u_i`` is data; Eq. 25's stray
``theta_{d,t}`` is read as ``theta_{i,k}``.
"""

from __future__ import annotations

from pyscipopt import quicksum

from expert.milp.variables import Milp


def add_push_constraints(milp: Milp) -> None:
    """Eq. 20-26 (stroke), once per piece, before the covered object's place, exclusions and precedences."""
    if not milp.problem.pushes.pushable:
        return
    _add_strokes(milp)
    _add_push_once(milp)
    _add_exclusions_and_precedences(milp)


def _add_strokes(milp: Milp) -> None:
    """Eq. 20-26: a push phase moves the base by its stroke, along one axis only."""
    problem, model, n = milp.problem, milp.model, milp.n_phases
    plan = problem.pushes
    di_max = max(abs(c.cells[0]) + abs(c.cells[1]) for c in plan.candidates)
    for k in range(1, n):
        chosen = milp.push_options_at(k)
        if not chosen:
            continue
        total = quicksum(z for _, z in chosen)
        for axis, coords, moved in ((0, milp.u, milp.mx), (1, milp.v, milp.my)):
            lo, hi = problem.grid.var_bounds(axis)
            big_m = (hi - lo) + di_max
            stroke = quicksum(problem.options[o].push.cells[axis] * z for o, z in chosen)
            delta = coords[k] - coords[k - 1] - stroke
            model.addCons(delta <= big_m * (1 - total), name=f"eq20_stroke_{axis}_{k}")
            model.addCons(delta >= -big_m * (1 - total), name=f"eq25_no_diagonal_{axis}_{k}")
            length = quicksum(abs(problem.options[o].push.cells[axis]) * z for o, z in chosen)
            model.addCons(moved[k] >= length, name=f"eq20_length_{axis}_{k}")


def _add_push_once(milp: Milp) -> None:
    """Each piece is pushed exactly once, before the place of every object whose goal it covers."""
    problem, model, n = milp.problem, milp.model, milp.n_phases
    plan = problem.pushes
    for clutter_id in plan.pushable:
        pushed = milp.pushed[clutter_id]
        for k in range(1, n):
            now = [z for o, z in milp.push_options_at(k) if problem.options[o].target == clutter_id]
            model.addCons(pushed[k] == pushed[k - 1] + quicksum(now), name=f"pushed_{clutter_id}_{k}")
        model.addCons(pushed[n - 1] == 1, name=f"push_once_{clutter_id}")
        for object_id, ids in problem.covers.items():
            if clutter_id not in ids:
                continue
            for k in range(1, n):
                places = milp.action_sum("place", object_id, k)
                if places is not None:
                    model.addCons(places <= pushed[k - 1], name=f"push_before_place_{clutter_id}_{object_id}_{k}")


def _add_exclusions_and_precedences(milp: Milp) -> None:
    """Strokes that exclude each other, room for the hand behind the piece, and pushes that must come after others."""
    model, n = milp.model, milp.n_phases
    plan = milp.problem.pushes
    uses = {index: milp.candidate_uses(index) for index in range(len(plan.candidates))}
    for a, b in plan.exclusive:
        if uses[a] is not None and uses[b] is not None:
            model.addCons(uses[a] + uses[b] <= 1, name=f"push_exclusive_{a}_{b}")
    for index, candidate in enumerate(plan.candidates):  # the hand needs the floor behind the piece free
        for object_id in candidate.hand_goals:
            if object_id not in milp.delta:
                continue
            for k in range(2, n):
                now = milp.candidate_at(index, k)
                if now is not None:
                    model.addCons(now <= 1 - milp.delta[object_id][k - 1], name=f"hand_room_{index}_{object_id}_{k}")
    for index, first in plan.precedence:
        for k in range(1, n):
            now = milp.candidate_at(index, k)
            if now is not None:
                model.addCons(now <= milp.pushed[first][k - 1], name=f"push_after_{first}_{index}_{k}")
