"""From a solved MILP to plan phases on the lattice, and the paper's objective of a plan.

Every base after the start is put on its lattice point (integer bases already are;
continuous ones are rounded to the nearest point, which :mod:`expert.milp.grid`
makes safe). A push's end is computed as the stroke's start plus the stroke, in
lattice cells, so that it is exact. Headings: the option's at picks, places and
pushes; a move keeps the previous heading (a round base needs no turn to travel).
Objects follow :func:`expert.milp.objects.object_position`: a held object is where
the hand is, at the robot-frame offset it was picked with.
"""

from __future__ import annotations

from dataclasses import dataclass

from expert.milp.options import PoseOption
from expert.milp.problem import Problem
from expert.plans import Phase
from fetchcarry_env.geometry import Heading, Point, to_robot_frame, to_world_frame


@dataclass(frozen=True)
class SolvedPhase:
    """One solved phase after the start: its lattice point and the option chosen (None: a move)."""

    cell: tuple[int, int]
    option: PoseOption | None


def read_steps(problem: Problem, milp, solution) -> list[SolvedPhase]:
    """The lattice point and option of every phase ``k >= 1`` of a solution."""
    model = milp.model
    steps: list[SolvedPhase] = []
    for k in range(1, milp.n_phases):
        chosen = [o for o, z in milp.z[k].items() if model.getSolVal(solution, z) > 0.5]
        option = problem.options[chosen[0]] if chosen else None
        cell = (round(model.getSolVal(solution, milp.u[k])), round(model.getSolVal(solution, milp.v[k])))
        if option is not None and option.push is not None:
            before = steps[-1].cell if steps else problem.start_index
            assert before is not None, "a push from the off-lattice start"
            cell = (before[0] + option.push.cells[0], before[1] + option.push.cells[1])
        steps.append(SolvedPhase(cell, option))
    return steps


def phases_of(problem: Problem, steps: list[SolvedPhase]) -> tuple[Phase, ...]:
    """The plan's phases: phase 0 (the start) and one per step, with every object and clutter position."""
    scenario = problem.scenario
    robot = scenario.robot
    objects = {o.id: o.start for o in scenario.objects}
    clutter = {c.id: c.rect.center for c in scenario.clutter}
    holding = problem.holding
    heading: Heading = robot.heading
    grip: Point | None = None
    if holding is not None:
        posture = robot.postures[0]
        grip = posture.center
        objects[holding] = _hand(robot.start, heading, grip)
    phases = [Phase(robot.start, heading, "start", None, None, holding, dict(objects), dict(clutter))]
    for step in steps:
        base = problem.grid.point(*step.cell)
        option = step.option
        action, target, posture = "move", None, None
        if option is not None:
            action, target, posture, heading = option.kind, option.target, option.posture, option.heading
            if option.kind == "pick":
                holding = option.target
                grip = to_robot_frame(heading, option.hand[0] - base[0], option.hand[1] - base[1])
            elif option.kind == "place":
                objects[option.target] = scenario.object(option.target).goal
                holding, grip = None, None
            else:
                cx, cy = clutter[option.target]
                dx, dy = option.push.cells
                resolution = problem.grid.resolution
                clutter[option.target] = (cx + dx * resolution, cy + dy * resolution)
        if holding is not None and grip is not None:
            objects[holding] = _hand(base, heading, grip)
        phases.append(Phase(base, heading, action, target, posture, holding, dict(objects), dict(clutter)))
    return tuple(phases)


def _hand(base: Point, heading: Heading, grip: Point) -> Point:
    dx, dy = to_world_frame(heading, grip[0], grip[1])
    return (base[0] + dx, base[1] + dy)
