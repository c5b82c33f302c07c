"""``plan(..., guide=...)``: a plan from elsewhere (a rollout too) as warm start and branching hint; same proof."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from cli_run import run

from expert.decoupled import steps_of
from expert.guide import compact_phases, guide_steps, snapped_steps
from expert.milp.problem import prepare
from expert.planner import plan
from expert.plans import Phase, Plan, task_cost
from expert.validate import validate_plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_covered, draw_paper_multi
from fetchcarry_env.scenario import Scenario
from training.guidance import rollout_plan

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"


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


def test_compact_phases_keep_the_actions_and_the_move_before_a_push():
    start = Phase((0.0, 0.0), "+x", "start")
    move = Phase((1.0, 0.0), "+x", "move")
    phases = (start, move, Phase((1.0, 1.0), "+x", "push", "block"), move, move, Phase((2.0, 0.0), "+x", "pick", "o"))
    assert [p.action for p in compact_phases(phases)] == ["start", "move", "push", "pick"]
    assert compact_phases((start, move)) == (start,)


@pytest.fixture(scope="module")
def greedy_guide():
    scenario = Scenario.load(EXAMPLE)
    return scenario, rollout_plan("greedy", scenario)


def test_a_rollout_is_a_valid_plan(greedy_guide):
    """Greedy's episode read back as phases passes the plan validator (what the env did is a plan)."""
    scenario, guide = greedy_guide
    assert guide.status == "feasible" and guide.stats["delivered"]
    assert validate_plan(scenario, guide) == []
    assert guide.objective == pytest.approx(task_cost(scenario, guide.phases))


@pytest.mark.parametrize("branching", [False, True])
def test_a_rollout_guide_keeps_the_optimum(greedy_guide, branching):
    scenario, guide = greedy_guide
    plain = plan(scenario, time_limit=60.0)
    guided = plan(scenario, time_limit=60.0, guide=guide, guide_branching=branching)
    assert guided.stats["guide"] == "mapped" and len(guided.stats["guide_phases"]) == 2  # as it is and compact
    assert guided.status == plain.status == "optimal"
    assert guided.objective == pytest.approx(plain.objective, abs=1e-6)


def test_plan_guide_on_the_command_line(capsys, tmp_path):
    status, out, _ = run(capsys, "plan", EXAMPLE, "--guide", "greedy", "--guide-branching")
    assert status == 0 and "guide      episode of greedy (delivered" in out
    status, _, err = run(capsys, "plan", EXAMPLE, "--guide", tmp_path / "missing")
    assert status == 2 and "not a plan file" in err
    status, _, err = run(capsys, "plan", EXAMPLE, "--guide-branching")
    assert status == 2 and "needs --guide" in err


def test_a_pose_outside_the_boxes_is_snapped_into_its_option(three_objects):
    """A pick from a base the MILP's pose boxes leave out (the env accepts more): mapped onto the nearest box."""
    scenario, plain = three_objects
    problem = prepare(scenario, Lattice.over(scenario.area, 0.05))
    k = next(k for k, p in enumerate(plain.phases) if p.action == "pick")
    moved = dataclasses.replace(plain.phases[k], base=(plain.phases[k].base[0] + 2.0, plain.phases[k].base[1]))
    phases = (*plain.phases[:k], moved, *plain.phases[k + 1 :])
    assert steps_of(problem, phases) is None
    steps = snapped_steps(problem, phases)
    assert steps is not None and len(steps) == len(phases) - 1
    step = steps[k - 1]
    assert step.option.kind == "pick" and step.option.target == moved.target and step.option.box.contains(*step.cell)
    assert guide_steps(problem, phases)  # the guide is used, not ignored
