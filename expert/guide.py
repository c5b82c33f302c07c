"""A guide plan (a learned policy's rollout, a greedy plan) as MILP steps for warm starts and branching hints.

A phase maps onto the option of its action, target, heading and posture whose pose box
holds its base (:func:`expert.decoupled.steps_of`). A rollout's poses are the env's,
and the env accepts some poses the MILP's boxes (rectangles inside the reachable set)
leave out; such a guide is mapped *snapped* (:func:`snapped_steps`): each action takes
the option of its action and target whose box is nearest (same heading and posture
first) and its base moves into that box (for a push, the base it strokes from).

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
    """The guide's MILP steps, as it is and compact (when shorter): each exactly if it maps, else snapped."""
    variants = [tuple(phases)]
    compact = compact_phases(phases)
    if len(compact) < len(phases):
        variants.append(compact)
    mapped = [steps_of(problem, v) or snapped_steps(problem, v) for v in variants if len(v) > 1]
    return [steps for steps in mapped if steps]


def snapped_steps(problem: Problem, phases: Sequence[Phase]) -> list[SolvedPhase] | None:
    """``phases`` after the start as MILP steps, each action on its nearest option, its base moved into the box.

    None when an action has no option at all (another scenario's plan, an object the
    MILP cannot act on) or a push would stroke from an off-lattice start.
    """
    lattice = problem.grid.lattice
    steps: list[SolvedPhase] = []
    previous = problem.start_index
    for phase in phases[1:]:
        cell = lattice.index(phase.base)
        if phase.action == "move":
            steps.append(SolvedPhase(cell, None))
            previous = cell
            continue
        acting = previous if phase.action == "push" else cell
        if acting is None:
            return None
        option = _nearest_option(problem, phase, acting)
        if option is None:
            return None
        inside = _clamp(acting, option.box)
        if phase.action == "push":
            if inside != acting:  # stroke from inside the box: the move before the push ends there
                if steps and steps[-1].option is None:
                    steps[-1] = SolvedPhase(inside, None)
                else:
                    steps.append(SolvedPhase(inside, None))
            cell = (inside[0] + option.push.cells[0], inside[1] + option.push.cells[1])
        else:
            cell = inside
        steps.append(SolvedPhase(cell, option))
        previous = cell
    return steps


def _nearest_option(problem: Problem, phase: Phase, cell: tuple[int, int]):
    """The option of ``phase``'s action and target nearest ``cell`` (same heading, then posture, first)."""
    options = [o for o in problem.options if o.kind == phase.action and o.target == phase.target]

    def rank(option) -> tuple[int, int, int]:
        i, j = _clamp(cell, option.box)
        return (option.heading != phase.heading, option.posture != phase.posture, abs(i - cell[0]) + abs(j - cell[1]))

    return min(options, key=rank, default=None)


def _clamp(cell: tuple[int, int], box) -> tuple[int, int]:
    """The point of ``box`` nearest ``cell`` (lattice indices)."""
    return (min(max(cell[0], box.i_lo), box.i_hi), min(max(cell[1], box.j_lo), box.j_hi))
