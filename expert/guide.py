"""A guide plan (a learned policy's rollout, a greedy plan) as MILP steps for warm starts and branching hints.

A rollout usually has more phases than the optimum: a policy stops on the way (moves
around a table, or short of a pose) where the MILP's phase moves straight. So besides
the guide as it is, :func:`guide_steps` maps its *compact* form: the moves dropped
except the one before a push (a push strokes from where the phase before it left the
base), so that each action follows the previous one directly. The compact plan is
a plan of the MILP only if those straight moves are free (the warm start checks every
constraint before SCIP takes it, :func:`expert.milp.warm.add_warm_start`); as a
branching hint it puts the guide's k-th action at phase k, where the optimum has it
when it takes the same actions in the same order.
"""

from __future__ import annotations

from collections.abc import Sequence

from expert.decoupled import steps_of
from expert.milp.decode import SolvedPhase
from expert.milp.problem import Problem
from expert.plans import Phase


def compact_phases(phases: Sequence[Phase]) -> tuple[Phase, ...]:
    """``phases`` without the moves, except a move followed by a push (the push's start)."""
    kept = [phases[0]] if phases else []
    for k, phase in enumerate(phases[1:], start=1):
        following = phases[k + 1].action if k + 1 < len(phases) else None
        if phase.action != "move" or following == "push":
            kept.append(phase)
    return tuple(kept)


def guide_steps(problem: Problem, phases: Sequence[Phase]) -> list[list[SolvedPhase]]:
    """The guide's MILP steps, as it is and compact (when shorter), each only if it maps onto the options."""
    variants = [tuple(phases)]
    compact = compact_phases(phases)
    if len(compact) < len(phases):
        variants.append(compact)
    mapped = [steps_of(problem, variant) for variant in variants if len(variant) > 1]
    return [steps for steps in mapped if steps]
