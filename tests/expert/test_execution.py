"""Each plan, executed action by action in ``FetchCarryPush-v0``, delivers every object, as planned.

The planner plans on the env's own lattice; :func:`plan_to_actions` turns the phases
into actions; the env (PyBullet) executes them. No action may be refused, every phase's
state is the planned one (the expert's tolerances: base 1 cm, items 2 cm), and the
episode must end, on the last action and not before, with every object delivered.
Without the simulator, the env's rules (:func:`fetchcarry_env.rules.check_action`)
must resolve every pick and push of a plan to the planned item: the planner models
which object a pick takes and which piece a push moves.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from planner_cases import BLOCK, bar, push_scene

import fetchcarry_env  # noqa: F401  (registers FetchCarryPush-v0)
from expert.milp.problem import prepare
from expert.planner import plan
from expert.plans import Phase
from expert.policy import BASE_TOLERANCE, ITEM_TOLERANCE
from expert.to_actions import plan_to_actions
from expert.tracking import departure
from expert.validate import validate_plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_push, get_family
from fetchcarry_env.observation import LIFT_HEIGHT, WorldState, standing_center
from fetchcarry_env.rules import check_action
from fetchcarry_env.scenario import DeliveryObject, Scenario

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"
TIME_LIMIT = 20.0  # seconds per planning call


def family_scenario(name: str, seed: int) -> Scenario:
    return get_family(name).sample(np.random.default_rng(seed))


CASES = {
    "spec example (push aside)": lambda: Scenario.load(EXAMPLE),
    "basic": lambda: family_scenario("basic", 1),
    "push": lambda: family_scenario("push", 2),
    "corridor": lambda: family_scenario("corridor", 3),
    "multi": lambda: family_scenario("multi", 4),
    "multi, 3 objects": lambda: family_scenario("multi", 7),
    "pattern E": lambda: draw_paper_push(np.random.default_rng(1), "E"),
}


def state_of(scenario: Scenario, phase: Phase) -> WorldState:
    """The world a plan phase describes (objects standing where it puts them, a held one lifted)."""
    objects = {}
    for obj in scenario.objects:
        x, y = phase.objects[obj.id][:2]
        z = standing_center(scenario, obj, obj.start if obj.id == phase.holding else (x, y))[2]
        objects[obj.id] = (x, y, z + (LIFT_HEIGHT if obj.id == phase.holding else 0.0))
    return WorldState(phase.base, phase.heading, phase.holding, objects, dict(phase.clutter))


PUSH_ASIDE = ("spec example (push aside)", "push")


@pytest.mark.parametrize("case", list(CASES))
def test_the_plan_delivers_every_object_in_the_env(case):
    scenario = CASES[case]()
    env = gym.make("FetchCarryPush-v0", scenario=scenario)
    try:
        env.reset(seed=0)
        lattice = env.unwrapped.lattice
        result = plan(scenario, time_limit=TIME_LIMIT, lattice=lattice)
        assert result.found, (case, result.status)
        assert validate_plan(scenario, result) == []
        if case in PUSH_ASIDE:  # clutter stands on a goal: the plan must push it aside
            assert any(p.action == "push" for p in result.phases)
        actions = plan_to_actions(result, scenario, lattice)
        assert len(actions) == len(result.phases) - 1
        for k, action in enumerate(actions, start=1):
            _, _, terminated, truncated, info = env.step(action.to_array())
            assert info["invalid_action"] is None, (case, k, result.phases[k], info["invalid_action"])
            assert not truncated, (case, k)
            assert terminated == (k == len(actions)), (case, k, info)
            gap = departure(result.phases[k], env.unwrapped.state, BASE_TOLERANCE, ITEM_TOLERANCE)
            assert gap is None, (case, k, gap)  # executed as planned
        assert info["is_success"], (case, info)
    finally:
        env.close()


def test_the_spec_example_pushes_while_carrying_and_places_at_the_stroke_s_end():
    """The paper's push-aside: pick, carry, push holding the bottle, place with no move between (6 phases)."""
    scenario = Scenario.load(EXAMPLE)
    result = plan(scenario, time_limit=TIME_LIMIT)
    actions = [p.action for p in result.phases]
    assert len(actions) == 6 and actions.count("pick") == 1 and actions[-2:] == ["push", "place"], actions
    push, place = result.phases[4], result.phases[5]
    assert result.phases[3].holding == "bottle" == push.holding
    assert place.base == push.base


AMBIGUITY_CASES = [("multi", seed) for seed in range(12)] + [("push", seed) for seed in range(8)]


@pytest.mark.parametrize(("family", "seed"), AMBIGUITY_CASES)
def test_every_pick_and_push_of_a_plan_acts_on_the_planned_item(family, seed):
    """The env's rules, applied to each phase's state, take exactly the planned object or piece."""
    scenario = family_scenario(family, seed)
    lattice = Lattice.over(get_family(family).extent, 0.05)
    result = plan(scenario, time_limit=TIME_LIMIT, lattice=lattice)
    assert result.found, result.status
    actions = plan_to_actions(result, scenario, lattice)
    for k, action in enumerate(actions, start=1):
        before, planned = result.phases[k - 1], result.phases[k]
        outcome = check_action(scenario, state_of(scenario, before), lattice, action)
        assert not isinstance(outcome, str), (k, planned.action, outcome)
        assert outcome.target == planned.target or planned.action == "move", (k, planned.action, outcome.target)


def test_a_push_whose_hand_stands_on_another_goal_comes_before_that_object_is_placed():
    """The cup's goal lies right behind the block (where the hand goes to push it +x): the env refuses that
    push once the cup stands there, and bars block the block's other ways, so the plan pushes first."""
    base = push_scene("hand-goal", {"block": BLOCK, "north": bar("+y"), "south": bar("-y")})
    cup = DeliveryObject("cup", (2.0, 2.12), (3.87, 3.97))
    scenario = dataclasses.replace(base, objects=(*base.objects, cup))
    lattice = Lattice.over(scenario.area, 0.05)
    candidates = {c.direction: c for c in prepare(scenario, lattice).pushes.candidates}
    assert candidates["+x"].hand_goals == ("cup",)
    result = plan(scenario, time_limit=TIME_LIMIT, lattice=lattice)
    assert result.found and validate_plan(scenario, result) == []
    actions = [(p.action, p.target) for p in result.phases]
    assert actions.index(("push", "block")) < actions.index(("place", "cup"))
    for k, action in enumerate(plan_to_actions(result, scenario, lattice), start=1):
        outcome = check_action(scenario, state_of(scenario, result.phases[k - 1]), lattice, action)
        assert not isinstance(outcome, str), (k, outcome)
