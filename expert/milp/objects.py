"""Objects follow the hand; delivery (the paper's Eq. 8-13).

Eq. 8-9 (object and hand coincide while picking, carrying and placing; an object not
held stays put) hold *by construction*: the only pose options that involve object
``i`` are picks at its start and places at its goal (:mod:`expert.milp.postures`), so
its position is the affine expression

    p_{i,k} = start_i * (1 - picked_{i,k}) + hand_k * gsp_{i,k} + goal_i * delta_{i,k},

with ``picked = gsp + delta`` (see :func:`object_position`). Substituting Eq. 8-9
into the model this way removes the object coordinates and their big-M rows; the
decoder (:mod:`expert.milp.decode`) evaluates the expression for the plan.

Eq. 10-13 (delivery):

- Eq. 10 (``delta`` only at the goal) holds by construction: objects reach their goal
  only by a place (``docs/design.md``: a place delivers).
- Eq. 12 is written with equality, ``delta_{i,k} = delta_{i,k-1} + theta^{plc}_{i,k}``,
  so ``delta`` is monotone (Eq. 13, left part) and Eq. 11 (``delta <= 1 - gsp``) follows:
  ``delta + gsp = (picked so far) <= 1``.
- Eq. 13, right part: ``delta_{i,N} = 1``, every object delivered in the last phase.

Also here: an object standing on another's goal is picked before that goal is used,
and a pick takes its target (the env takes the object within reach nearest the middle
of the posture's ranges, ``fetchcarry_env.rules``): a pick option from whose bases the
env would take another object standing somewhere (:attr:`expert.milp.options.PoseOption.confusers`,
:func:`expert.milp.options.split_by_choice`) is forbidden while that object stands there
(:func:`add_pick_confusion_constraints`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pyscipopt import quicksum

from fetchcarry_env.geometry import Point

if TYPE_CHECKING:
    from expert.milp.variables import Milp


def object_position(start: Point, goal: Point, hand: Point, picked: float, held: float, delivered: float) -> Point:
    """Eq. 8-9 as an expression: where object ``i`` is, given its pick/hold/delivery state (0 or 1 each)."""
    return (
        start[0] * (1 - picked) + hand[0] * held + goal[0] * delivered,
        start[1] * (1 - picked) + hand[1] * held + goal[1] * delivered,
    )


def add_delivery_constraints(milp: Milp) -> None:
    """Eq. 10-13 and the order imposed by objects that stand on other objects' goals."""
    model, n = milp.model, milp.n_phases
    for object_id in milp.problem.deliver:
        delta = milp.delta[object_id]
        for k in range(1, n):
            places = milp.action_sum("place", object_id, k)
            model.addCons(
                delta[k] == delta[k - 1] + (places if places is not None else 0), name=f"eq12_{object_id}_{k}"
            )
        model.addCons(delta[n - 1] == 1, name=f"eq13_delivered_{object_id}")
    add_delivery_timing(milp)
    for goal_owner, standing in milp.problem.blocking_objects:
        for k in range(2, n):
            places = milp.action_sum("place", goal_owner, k)
            if places is not None:
                picked = milp.gsp[standing][k - 1] + milp.delta[standing][k - 1]
                model.addCons(places <= picked, name=f"clear_goal_{goal_owner}_{standing}_{k}")
    add_pick_confusion_constraints(milp)


def add_pick_confusion_constraints(milp: Milp) -> None:
    """No pick with another object within reach: ``sum_{o confused by (j, where)} z_{o,k} <= 1 - [j there at k]``.

    ``j`` stands at its start until it is picked (``1 - gsp_{j,k-1} - delta_{j,k-1}``) and at
    its goal once delivered (``delta_{j,k-1}``); one action per phase, so phase k-1's state
    is the one the pick sees.
    """
    problem, model = milp.problem, milp.model
    for k in range(1, milp.n_phases):
        groups: dict = {}
        for o, z in milp.arm_options_at(k):
            for state in sorted(problem.options[o].confusers):  # a fixed order: not the set's, which hashing decides
                groups.setdefault(state, []).append(z)
        for state, terms in groups.items():
            j = state.object_id
            picked = milp.gsp[j][k - 1] + milp.delta[j][k - 1]
            allowed = picked if state.where == "start" else 1 - milp.delta[j][k - 1]
            model.addCons(quicksum(terms) <= allowed, name=f"pick_takes_target_{j}_{state.where}_{k}")


def add_delivery_timing(milp: Milp) -> None:
    """Valid inequalities on how many objects can be delivered by phase k (they tighten the LP of Eq. 1).

    Early: ``sum_i delta_{i,k} <= d - 1`` while ``k < earliest[d]`` (the skeleton relaxation,
    :class:`expert.milp.bounds.Skeleton`), and in any case ``2 * delivered - held0 + pushed <= k``
    (each delivery needs its own pick and place phase). Late: what is left after phase
    k needs its phases, ``2 * (undelivered) - (held at k) + (pushes left) <= N - 1 - k``.
    """
    problem, model, n = milp.problem, milp.model, milp.n_phases
    objects = problem.deliver
    count = len(objects)
    held0 = 1 if problem.holding is not None else 0
    for k in range(1, n):
        delivered = quicksum(milp.delta[i][k] for i in objects)
        pushed = quicksum(milp.pushed[c][k] for c in problem.pushes.pushable)
        cap = max((d for d, t in enumerate(problem.earliest) if t <= k), default=count)
        if cap < count:
            model.addCons(delivered <= cap, name=f"earliest_delivery_{k}")
        model.addCons(2 * delivered + pushed <= k + held0, name=f"actions_so_far_{k}")
        held = quicksum(milp.gsp[i][k] for i in objects)
        pushes_left = len(problem.pushes.pushable) - pushed
        model.addCons(2 * (count - delivered) - held + pushes_left <= n - 1 - k, name=f"actions_left_{k}")
