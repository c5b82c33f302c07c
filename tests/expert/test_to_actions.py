"""plan_to_actions: one env action per phase after the start, exactly on the lattice or refused."""

from __future__ import annotations

from dataclasses import replace

import pytest
from handmade import with_phase

from expert.to_actions import plan_to_actions
from fetchcarry_env.actions import Lattice, Mode


@pytest.fixture
def lattice(spec_example) -> Lattice:
    """A 1 cm lattice: the hand-written plan's bases (3.28, 3.43, ...) all lie on it."""
    return Lattice.over(spec_example.area, 0.01)


def test_each_phase_becomes_one_action(spec_example, hand_plan, lattice):
    actions = plan_to_actions(hand_plan, spec_example, lattice)
    assert len(actions) == len(hand_plan.phases) - 1
    modes = [a.mode for a in actions]
    assert modes == [Mode.MOVE, Mode.MOVE, Mode.PUSH, Mode.MOVE, Mode.PICK, Mode.MOVE, Mode.PLACE]
    push = actions[2]  # phase 3
    assert lattice.point(*push.cell) == pytest.approx(hand_plan.phases[3].base)
    assert push.heading == "+y" and push.posture == 0  # reach_far is the first posture
    assert actions[0].posture == 0 and actions[0].heading == "+y"


def test_the_posture_index_follows_the_scenario(spec_example, hand_plan, lattice):
    near = with_phase(hand_plan, 5, posture="reach_near")
    assert plan_to_actions(near, spec_example, lattice)[4].posture == 1


def test_a_base_off_the_lattice_is_refused_naming_the_phase(spec_example, hand_plan, lattice):
    with pytest.raises(ValueError, match=r"^phase 2: base \[4.0, 3.275\] is not a point of the lattice"):
        plan_to_actions(with_phase(hand_plan, 2, base=(4.0, 3.275)), spec_example, lattice)
    with pytest.raises(ValueError, match=r"^phase 1: base \[7.0, 0.0\] is not a point of the lattice"):
        plan_to_actions(with_phase(hand_plan, 1, base=(7.0, 0.0)), spec_example, lattice)  # beyond the lattice


def test_unknown_postures_and_empty_plans_are_refused(spec_example, hand_plan, lattice):
    with pytest.raises(ValueError, match=r"^phase 5: posture 'reach_up' is not one of"):
        plan_to_actions(with_phase(hand_plan, 5, posture="reach_up"), spec_example, lattice)
    with pytest.raises(ValueError, match="has no phases"):
        plan_to_actions(replace(hand_plan, status="infeasible", phases=()), spec_example, lattice)


def test_a_push_while_carrying_is_a_push_action_then_a_place_on_the_same_cell(spec_example):
    """The planner's plan for the spec example: pick, carry, push holding the bottle, place at the stroke's end."""
    from expert.planner import plan

    lattice = Lattice.over(spec_example.area, 0.05)
    result = plan(spec_example, lattice=lattice)
    actions = plan_to_actions(result, spec_example, lattice)
    modes = [a.mode for a in actions]
    assert len(modes) == 5 and modes.count(Mode.PICK) == 1 and modes[-2:] == [Mode.PUSH, Mode.PLACE], modes
    push, place = actions[3], actions[4]
    assert result.phases[3].holding == "bottle"  # the hand is full when the stroke starts
    assert place.cell == push.cell  # no move between the stroke's end and the place
    assert push.posture == 0  # reach_far
