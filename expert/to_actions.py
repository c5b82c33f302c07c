"""A plan as the environment's actions: one :class:`~fetchcarry_env.actions.Action` per phase.

Phase 0 is the start state and has no action; every later phase ``k`` becomes the
action that sends the base to the phase's lattice point, with the phase's heading,
posture and mode (``docs/design.md``: one action is one phase). The planner puts its
bases on the env's lattice, so the conversion is exact or refused.
"""

from __future__ import annotations

from expert.plans import Phase, Plan
from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.scenario import Scenario

MODES: dict[str, Mode] = {"move": Mode.MOVE, "pick": Mode.PICK, "place": Mode.PLACE, "push": Mode.PUSH}
"""The env's mode for each phase action after the start."""

ON_LATTICE_TOL = 1e-6  # metres: how far a base may lie from its lattice point and still count as on it


def plan_to_actions(plan: Plan, scenario: Scenario, lattice: Lattice) -> list[Action]:
    """The env actions that execute ``plan``'s phases 1.. in order.

    Raises ``ValueError`` naming the phase when a base is not exactly on ``lattice``
    (or outside it), when a posture is not one of the scenario's robot, or when a phase
    after the first is a ``start``; and when the plan has no phases (no plan found).
    """
    if not plan.phases:
        raise ValueError(f"plan for {plan.scenario!r} has no phases (status {plan.status!r}): nothing to execute")
    posture_index = {posture.name: index for index, posture in enumerate(scenario.robot.postures)}
    return [_action(k, phase, lattice, posture_index) for k, phase in enumerate(plan.phases) if k >= 1]


def _action(k: int, phase: Phase, lattice: Lattice, posture_index: dict[str, int]) -> Action:
    if phase.action not in MODES:
        raise ValueError(f"phase {k}: action {phase.action!r} has no env action (only phase 0 may be 'start')")
    cell = lattice.index(phase.base)
    if not lattice.on_lattice(phase.base, tol=ON_LATTICE_TOL):
        raise ValueError(
            f"phase {k}: base {list(phase.base)} is not a point of the lattice "
            f"(origin {list(lattice.origin)}, resolution {lattice.resolution} m, shape {list(lattice.shape)})"
        )
    if phase.action == "move":
        posture = 0
    elif phase.posture in posture_index:
        posture = posture_index[phase.posture]
    else:
        raise ValueError(f"phase {k}: posture {phase.posture!r} is not one of {sorted(posture_index)}")
    return Action(cell=cell, heading=phase.heading, posture=posture, mode=MODES[phase.action])
