"""A valid hand-written plan for the spec's example scenario.

The plan for ``examples/push_basic.json`` (start (0, 0), the bottle from the table at
(2, 2) to the goal table at (4, 4), where the clutter ``block`` stands on the goal):
drive round the tables, push the block 0.15 m along +y off the goal, fetch the bottle
from the west side of its table and place it from the south of the goal table.
The comments give the numbers that make each phase valid (reach_far: 0.55-0.70 m ahead).
Its objective (the task cost) is worked out here apart from the validator: every move is
axis-aligned, so the travel cost is 1.1 x the 13.06 m driven, and the bottle reaches its
goal in the last of the eight phases, so it waits six (phases 1 to 6 end without it at its
goal): 14.366 + 10 x 6 = 74.366.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

from expert.plans import Phase, Plan

BOTTLE_START = (2.0, 2.0)
BLOCK_START = (4.0, 4.0)
BLOCK_PUSHED = (4.0, 4.15)  # 0.15 m along +y: off the goal disc, still on table_goal
BOTTLE_GOAL = (4.0, 4.0)
HAND_OBJECTIVE = 1.1 * 13.06 + 10.0 * 6  # the task cost of HAND_PHASES (see above)


def _phase(base, heading, action, target=None, posture=None, holding=None, bottle=BOTTLE_START, block=BLOCK_START):
    return Phase(base, heading, action, target, posture, holding, {"bottle": bottle}, {"block": block})


HAND_PHASES = (
    _phase((0.0, 0.0), "+x", "start"),
    _phase((4.0, 0.0), "+y", "move"),
    _phase((4.0, 3.28), "+y", "move"),  # the push contact (4.0, 3.88) is 0.60 m ahead
    _phase((4.0, 3.43), "+y", "push", "block", "reach_far", block=BLOCK_PUSHED),
    _phase((4.0, 2.0), "-x", "move", block=BLOCK_PUSHED),  # east of box_1 (x <= 3.2), below table_goal
    _phase((2.6, 2.0), "-x", "pick", "bottle", "reach_far", "bottle", block=BLOCK_PUSHED),  # 0.60 m ahead
    _phase((4.0, 2.0), "+y", "move", holding="bottle", bottle=(4.0, 2.6), block=BLOCK_PUSHED),
    _phase((4.0, 3.4), "+y", "place", "bottle", "reach_far", None, bottle=(4.0, 4.0), block=BLOCK_PUSHED),  # 0.60
)


def cost(phases) -> float:
    """The task cost of phases of the example scenario (one object, the bottle), from its definition.

    ``10`` per phase after the start that ends with the bottle held or away from its goal
    (farther than 1 mm), plus ``|dx| + |dy| + 0.1 * ||dx| - |dy||`` per move.
    """
    waiting = sum(
        p.holding == "bottle" or math.dist(p.objects.get("bottle", (1e9, 1e9)), BOTTLE_GOAL) > 1e-3 for p in phases[1:]
    )
    travel = 0.0
    for a, b in itertools.pairwise(phases):
        dx, dy = abs(b.base[0] - a.base[0]), abs(b.base[1] - a.base[1])
        travel += dx + dy + 0.1 * abs(dx - dy)
    return travel + 10.0 * waiting


def with_phases(plan: Plan, phases) -> Plan:
    """``plan`` with these phases and its objective recomputed (the task cost), so only the fault put in is wrong."""
    return replace(plan, phases=tuple(phases), objective=cost(phases))


def with_phase(plan: Plan, k: int, **changes) -> Plan:
    """``plan`` with phase ``k``'s fields replaced (and the objective recomputed)."""
    phases = list(plan.phases)
    phases[k] = replace(phases[k], **changes)
    return with_phases(plan, phases)


def hand_plan_for(scenario_name: str) -> Plan:
    """The hand-written plan as a :class:`Plan` for the scenario named ``scenario_name``."""
    return Plan(scenario_name, "optimal", HAND_OBJECTIVE, HAND_PHASES, {"total_s": 0.0})
