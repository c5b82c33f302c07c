"""``plan(..., guide=...)``: a plan from elsewhere as warm start and branching hint; the same answer and proof."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from expert.planner import plan
from expert.plans import Plan
from fetchcarry_env.families import draw_paper_covered, draw_paper_multi


@pytest.fixture(scope="module")
def three_objects():
    scenario = draw_paper_multi(np.random.default_rng(11), 3)
    return scenario, plan(scenario, time_limit=60.0)


@pytest.mark.parametrize("branching", [False, True])
def test_a_guide_keeps_the_optimum(three_objects, branching):
    scenario, plain = three_objects
    assert plain.status == "optimal"
    guided = plan(scenario, time_limit=60.0, guide=plain, guide_branching=branching)
    assert guided.status == "optimal" and guided.stats["guide"] == "mapped"
    assert guided.objective == pytest.approx(plain.objective, abs=1e-6)
    last = guided.stats["solves"][-1]
    assert last["warm_start"] is True  # the optimal plan fits its own model
    assert (last.get("guide_priorities", 0) > 0) is branching


def test_a_worse_guide_keeps_the_optimum(three_objects):
    """A valid plan with an idle phase more than the optimum's: no model it fits is solved, the answer is the same."""
    scenario, plain = three_objects
    idle = dataclasses.replace(plain.phases[-1], action="move", target=None, posture=None)
    padded = Plan(plain.scenario, "feasible", None, (*plain.phases, idle), {})
    guided = plan(scenario, time_limit=60.0, guide=padded, guide_branching=True)
    assert guided.status == "optimal" and guided.objective == pytest.approx(plain.objective, abs=1e-6)


def test_a_guide_for_another_scenario_is_ignored(three_objects):
    scenario, plain = three_objects
    other = plan(draw_paper_covered(np.random.default_rng(1), 2), time_limit=60.0)
    guided = plan(scenario, time_limit=60.0, guide=other)
    assert guided.stats["guide"] == "not mappable (ignored)"
    assert guided.objective == pytest.approx(plain.objective, abs=1e-6)
