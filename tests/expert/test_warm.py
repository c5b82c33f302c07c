"""Warm starts: a plan is handed to SCIP only when it is feasible in the model (``checkSol``, not ``addSol``)."""

from __future__ import annotations

import numpy as np
import pytest

from expert.decoupled import decoupled_plan, steps_of
from expert.milp.build import build
from expert.milp.deadline import Deadline
from expert.milp.decode import SolvedPhase
from expert.milp.problem import prepare
from expert.milp.warm import add_warm_start
from expert.planner import PlannerOptions, SubPlanner
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_multi


@pytest.fixture(scope="module")
def two_objects():
    """A two-object scenario, its problem and the decoupled plan's steps (a feasible plan)."""
    scenario = draw_paper_multi(np.random.default_rng(1), 2)
    lattice = Lattice.over(scenario.area, 0.05)
    sub_planner = SubPlanner(PlannerOptions(), Deadline.after(120.0), lattice)
    phases = decoupled_plan(scenario, [o.id for o in scenario.objects], lattice, sub_planner)
    problem = prepare(scenario, lattice)
    return problem, steps_of(problem, phases), len(phases)


def test_a_feasible_plan_is_accepted(two_objects):
    problem, steps, n = two_objects
    milp = build(problem, n)
    assert add_warm_start(milp, steps) is True
    assert milp.model.getNSols() == 1


@pytest.mark.parametrize("shift", [3, 15])
def test_a_plan_acting_outside_its_pose_box_is_refused(two_objects, shift):
    """A pick done ``shift`` cells off its option's box: infeasible, so not accepted (``addSol`` said True)."""
    problem, steps, n = two_objects
    k = next(i for i, step in enumerate(steps) if step.option is not None)
    i, j = steps[k].cell
    assert not steps[k].option.box.contains(i + shift, j + shift)
    bad = list(steps)
    bad[k] = SolvedPhase((i + shift, j + shift), steps[k].option)
    milp = build(problem, n)
    assert add_warm_start(milp, bad) is False
    assert milp.model.getNSols() == 0  # and not stored as SCIP's incumbent either
