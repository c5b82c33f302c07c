"""The plan validator: a valid hand-written plan passes, and each broken rule is named with its phase and ids.

Every broken plan below is the valid hand-written plan of ``handmade.py`` with one
fault put in; the test asserts the message a user would read.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest
from handmade import BOTTLE_START, HAND_OBJECTIVE, HAND_PHASES, cost, with_phase, with_phases
from hypothesis import given, settings
from hypothesis import strategies as st

from expert.plans import PHASE_ACTIONS, STATUSES, Phase, Plan, task_cost
from expert.validate import validate_plan
from fetchcarry_env.geometry import HEADINGS
from fetchcarry_env.scenario import Scenario

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"


def with_block(plan: Plan, from_k: int, center) -> Plan:
    """``plan`` with the clutter ``block`` at ``center`` from phase ``from_k`` on."""
    phases = [
        replace(p, clutter={**p.clutter, "block": center}) if k >= from_k else p for k, p in enumerate(plan.phases)
    ]
    return with_phases(plan, phases)


def test_the_hand_written_plan_is_valid(spec_example, hand_plan):
    assert validate_plan(spec_example, hand_plan) == []


def test_positions_within_one_millimetre_are_accepted(spec_example, hand_plan):
    nudged = with_phase(hand_plan, 7, objects={"bottle": (4.0008, 3.9995)})
    assert validate_plan(spec_example, nudged) == []
    off = with_phase(hand_plan, 7, objects={"bottle": (4.002, 4.0)})
    assert any(
        m.startswith("rule 6 (goal): in the last phase (7) object 'bottle'") for m in validate_plan(spec_example, off)
    )


def test_a_plan_without_phases_is_not_valid(spec_example):
    plan = Plan(spec_example.name, "infeasible", None, (), {"total_s": 0.1})
    assert validate_plan(spec_example, plan) == ["structure: the plan has no phases to check (status 'infeasible')"]


# ---------------------------------------------------------------------- structure
@pytest.mark.parametrize(
    ("k", "changes", "message"),
    [
        (0, {"base": (0.1, 0.0)}, "structure: phase 0 base [0.100, 0.000] is not robot.start [0.000, 0.000]"),
        (0, {"action": "move"}, "structure: phase 0 must be 'start', not 'move'"),
        (0, {"heading": "-y"}, "structure: phase 0 heading '-y' is not the robot's heading '+x'"),
        (
            0,
            {"objects": {"bottle": (2.0, 2.02)}},
            "structure: phase 0 object 'bottle' is at [2.000, 2.020], not its start [2.000, 2.000]",
        ),
        (4, {"clutter": {}}, "structure: phase 4 lacks clutter 'block'"),
        (
            2,
            {"objects": {"bottle": BOTTLE_START, "ghost": (1.0, 1.0)}},
            "structure: phase 2 names unknown object 'ghost'",
        ),
        (
            5,
            {"posture": "reach_sideways"},
            "structure: phase 5 pick posture 'reach_sideways' is not a posture of the robot",
        ),
        (5, {"target": "block"}, "structure: phase 5 pick target 'block' is not a object id of the scenario"),
        (1, {"target": "bottle"}, "structure: phase 1 move must have no target and no posture"),
        (3, {"action": "start"}, "structure: phase 3 is a second 'start'"),
    ],
)
def test_structure_faults_are_named(spec_example, hand_plan, k, changes, message):
    assert message in validate_plan(spec_example, with_phase(hand_plan, k, **changes))


def test_a_plan_for_another_scenario_is_named(spec_example, hand_plan):
    violations = validate_plan(spec_example, replace(hand_plan, scenario="other"))
    assert violations == ["structure: the plan is for scenario 'other', not 'basic-area3-07'"]


# ---------------------------------------------------------------------- rule 1
@pytest.mark.parametrize(
    ("k", "base", "message"),
    [
        pytest.param(
            1,
            (4.0, -0.9),  # the disc reaches y = -1.12 < -1.0
            "rule 1 (area): phase 1 base disc at [4.000, -0.900] is not inside the area",
            id="rule1-base-outside-the-area",
        ),
        pytest.param(
            1,
            (3.0, 2.0),  # from (0, 0) to (3, 2) the base centre passes 0.139 m from table_src's corner (2.3, 1.7)
            "rule 1 (clearance): phase 1 move from [0.000, 0.000] to [3.000, 2.000] passes 0.139 m from table "
            "'table_src', less than the base radius 0.220 m",
            id="rule1-a-move-that-grazes-a-table",
        ),
        pytest.param(
            5,
            (2.8, 2.0),
            "rule 4 (reach): phase 5 pick 'bottle' is 0.800 m ahead, outside posture 'reach_far' forward range "
            "[0.550, 0.700]",
            id="rule4-target-too-far-ahead",
        ),
        pytest.param(
            5,
            (2.6, 2.1),  # facing -x, the robot's left is -y: the bottle at y = 2.0 is 0.1 m to the left
            "rule 4 (reach): phase 5 pick 'bottle' is 0.100 m to the left (lateral 0.100), outside posture "
            "'reach_far' lateral range [-0.050, 0.050]",
            id="rule4-target-off-to-the-side",
        ),
    ],
)
def test_a_base_moved_breaks_exactly_one_rule(spec_example, hand_plan, k, base, message):
    assert validate_plan(spec_example, with_phase(hand_plan, k, base=base)) == [message]


def test_rule1_a_move_across_a_table_and_past_an_obstacle(spec_example, hand_plan):
    plan = with_phases(hand_plan, hand_plan.phases[:1] + hand_plan.phases[2:])  # straight on to (4.0, 3.28)
    violations = validate_plan(spec_example, plan)
    clearance = [m for m in violations if m.startswith("rule 1 (clearance): phase 1 move from [0.000, 0.000]")]
    assert len(clearance) == 2, violations
    assert "passes 0.000 m from table 'table_src', less than the base radius 0.220 m" in clearance[0]
    assert "obstacle 'box_1'" in clearance[1]


# ---------------------------------------------------------------------- rule 2
def test_rule2_holding_changes_outside_pick_and_place(spec_example, hand_plan):
    violations = validate_plan(spec_example, with_phase(hand_plan, 6, holding=None))
    assert (
        "rule 2 (holding): phase 6 move changes holding from 'bottle' to None; only a pick or a place may"
    ) in violations
    assert "rule 2 (holding): phase 7 place 'bottle' while holding None, not 'bottle'" in violations


def test_rule2_a_pick_that_holds_nothing(spec_example, hand_plan):
    violations = validate_plan(spec_example, with_phase(hand_plan, 5, holding=None))
    assert "rule 2 (holding): phase 5 pick 'bottle' ends holding None, not 'bottle'" in violations


# ---------------------------------------------------------------------- rule 3
def test_rule3_an_object_that_moves_by_itself(spec_example, hand_plan):
    violations = validate_plan(spec_example, with_phase(hand_plan, 4, objects={"bottle": (2.05, 2.0)}))
    assert (
        "rule 3 (objects stay): phase 4 object 'bottle' moves from [2.000, 2.000] to [2.050, 2.000] "
        "although it is not held"
    ) in violations


# ---------------------------------------------------------------------- rule 4
def test_rule4_placing_onto_clutter_across_the_arm_line(spec_example, hand_plan):
    # Skip the push: the block still stands on the goal when the bottle is placed there.
    phases = [p for k, p in enumerate(hand_plan.phases) if k not in (2, 3)]
    plan = with_block(with_phases(hand_plan, phases), 0, (4.0, 4.0))
    assert validate_plan(spec_example, plan) == [
        "rule 4 (arm line): phase 5 place 'bottle': the arm line from [4.000, 3.400] to [4.000, 4.000] "
        "crosses clutter 'block'",
        "rule 4 (place): phase 5 place 'bottle' at [4.000, 4.000] overlaps clutter 'block'",
    ]


def test_rule4_placing_off_the_table(spec_example, hand_plan):
    plan = with_phase(hand_plan, 7, base=(4.0, 3.0), objects={"bottle": (4.0, 3.6)})
    violations = validate_plan(spec_example, plan)
    assert "rule 4 (place): phase 7 place 'bottle' at [4.000, 3.600] does not stand fully on a table" in violations
    assert (
        "rule 4 (place): phase 7 place 'bottle' at [4.000, 3.600] is not at its goal [4.000, 4.000] "
        "(docs/design.md: a place delivers)"
    ) in violations


# ---------------------------------------------------------------------- rule 5
def test_rule5_clutter_that_moves_outside_a_push(spec_example, hand_plan):
    violations = validate_plan(spec_example, with_block(hand_plan, 4, (4.0, 4.2)))
    assert violations == [
        "rule 5 (push): phase 4 clutter 'block' moves from [4.000, 4.150] to [4.000, 4.200] outside a push of it"
    ]


def test_rule5_a_diagonal_stroke(spec_example, hand_plan):
    plan = with_block(with_phase(hand_plan, 3, base=(4.05, 3.43)), 3, (4.05, 4.15))
    assert (
        "rule 5 (push): phase 3 push 'block': the stroke [0.050, 0.150] is not axis-aligned (no diagonal or "
        "empty pushes)"
    ) in validate_plan(spec_example, plan)


def test_rule5_clutter_that_moves_more_than_the_stroke(spec_example, hand_plan):
    violations = validate_plan(spec_example, with_block(hand_plan, 3, (4.0, 4.2)))
    assert violations == [
        "rule 5 (push): phase 3 push 'block': the clutter moves by [0.000, 0.200], not by the base's stroke "
        "[0.000, 0.150]"
    ]


def lateral_push_plan(hand_plan: Plan, stroke: float) -> Plan:
    """The hand plan with a lateral push instead: facing +y, the base strokes ``stroke`` metres along +x."""
    start = Phase((3.9, 3.4), "+y", "move", None, None, None, {"bottle": BOTTLE_START}, {"block": (4.0, 4.0)})
    # The contact for +x is the middle of the block's west face less the hand: (3.88, 4.0), 0.60 m ahead.
    push = replace(start, base=(3.9 + stroke, 3.4), action="push", target="block", posture="reach_far")
    phases = (*hand_plan.phases[:2], start, push, *hand_plan.phases[4:])
    return with_block(with_phases(hand_plan, phases), 3, (4.0 + stroke, 4.0))


def test_rule5_a_lateral_push_is_valid(spec_example, hand_plan):
    assert validate_plan(spec_example, lateral_push_plan(hand_plan, 0.15)) == []


def test_rule5_pushing_clutter_off_its_table(spec_example, hand_plan):
    violations = validate_plan(spec_example, lateral_push_plan(hand_plan, 0.3))
    assert violations == [
        "rule 5 (push): phase 3 push 'block': the clutter ends at [4.300, 4.000], not fully on its table 'table_goal'"
    ]


def test_rule5_pushing_clutter_into_other_clutter(spec_example_dict, hand_plan):
    spec_example_dict["clutter"].append({"id": "cube", "min": [3.95, 4.2], "max": [4.05, 4.28]})
    scenario = Scenario.from_dict(spec_example_dict)
    phases = tuple(replace(p, clutter={**p.clutter, "cube": (4.0, 4.24)}) for p in hand_plan.phases)
    violations = validate_plan(scenario, with_phases(hand_plan, phases))
    assert violations == ["rule 5 (push): phase 3 push 'block': the clutter runs into clutter 'cube'"]


def test_rule5_pushing_backwards(spec_example, hand_plan):
    violations = validate_plan(spec_example, with_phase(hand_plan, 3, heading="-y"))
    assert (
        "rule 5 (push): phase 3 push 'block': heading '-y' pushes backwards along '+y' (docs/design.md)" in violations
    )
    assert (
        "rule 9 (hand room): phase 3 push 'block': the push contact is -0.600 m ahead, outside posture 'reach_far' "
        "forward range [0.550, 0.700]"
    ) in violations


def test_rule5_push_contact_out_of_reach(spec_example, hand_plan):
    plan = with_phase(with_phase(hand_plan, 2, base=(4.0, 3.1)), 3, base=(4.0, 3.25))
    assert validate_plan(spec_example, plan) == [
        "rule 9 (hand room): phase 3 push 'block': the push contact is 0.780 m ahead, outside posture 'reach_far' "
        "forward range [0.550, 0.700]"
    ]


def test_rule5_pushing_with_an_object_in_the_hand_is_allowed(spec_example, hand_plan):
    """The paper's push-aside while carrying: the held bottle moves with the base through the stroke."""
    p = hand_plan.phases
    phases = (  # the bottle, picked 0.6 m ahead, moves with the base facing +y
        p[0],
        replace(p[4], base=(2.6, 0.0), clutter={"block": (4.0, 4.0)}),  # south of table_src
        replace(p[5], clutter={"block": (4.0, 4.0)}),  # pick the bottle first
        replace(p[2], holding="bottle", objects={"bottle": (4.0, 3.88)}),
        replace(p[3], holding="bottle", objects={"bottle": (4.0, 4.03)}),
        p[7],
    )
    assert validate_plan(spec_example, with_phases(hand_plan, phases)) == []


# ---------------------------------------------------------------------- rule 6
def test_rule6_a_plan_that_stops_short(spec_example, hand_plan):
    violations = validate_plan(spec_example, with_phases(hand_plan, hand_plan.phases[:7]))
    assert violations == [
        "rule 6 (goal): in the last phase (6) object 'bottle' is at [4.000, 2.600], 1.400 m from its goal "
        "[4.000, 4.000]",
        "rule 6 (goal): in the last phase (6) the robot still holds 'bottle'",
    ]


def test_every_violation_is_listed(spec_example, hand_plan):
    """Two independent faults give (at least) both messages, in rule order."""
    plan = with_phase(with_phase(hand_plan, 1, base=(4.0, -0.9)), 5, base=(2.8, 2.0))
    violations = validate_plan(spec_example, plan)
    assert [m.split(":")[0] for m in violations] == ["rule 1 (area)", "rule 4 (reach)"]


# ---------------------------------------------------------------------- rule 7
def test_rule7_a_held_object_reported_far_from_the_hand(spec_example, hand_plan):
    """Issue 8: a carried object reported at (50, -50) was accepted."""
    violations = validate_plan(spec_example, with_phase(hand_plan, 6, objects={"bottle": (50.0, -50.0)}))
    assert violations == [
        "rule 7 (held object): phase 6 move holding 'bottle': it is -52.000 m ahead, outside posture 'reach_far' "
        "forward range [0.550, 0.700]",
        "rule 7 (held object): phase 6 move holding 'bottle': it is 46.000 m to the right (lateral -46.000), outside "
        "posture 'reach_far' lateral range [-0.050, 0.050]",
        "rule 7 (held object): phase 6 move holding 'bottle': it is at [50.000, -50.000], not in the hand at "
        "[4.000, 2.600] (it moves with the base, at the offset [0.600, 0.000] ahead/left it was picked with)",
    ]


def test_rule7_a_held_object_that_slides_in_the_hand(spec_example, hand_plan):
    """Within the posture's ranges but not where the grasp put it: it must move with the base."""
    violations = validate_plan(spec_example, with_phase(hand_plan, 6, objects={"bottle": (4.0, 2.68)}))
    assert violations == [
        "rule 7 (held object): phase 6 move holding 'bottle': it is at [4.000, 2.680], not in the hand at "
        "[4.000, 2.600] (it moves with the base, at the offset [0.600, 0.000] ahead/left it was picked with)"
    ]


def test_rule7_a_held_object_turns_with_the_base(spec_example, hand_plan):
    """Facing -y instead of +y after the pick, the hand (0.6 m ahead) is south of the base."""
    plan = with_phase(hand_plan, 6, heading="-y", objects={"bottle": (4.0, 1.4)})
    assert not [v for v in validate_plan(spec_example, plan) if v.startswith("rule 7")]


def test_rule7_held_before_the_plan_starts(spec_example):
    """A mid-episode plan (``holding=``): the object must lie within some posture's ranges."""
    start = HAND_PHASES[0]
    phases = (replace(start, holding="bottle", objects={"bottle": (0.6, 0.0)}),)
    plan = Plan(spec_example.name, "feasible", cost(phases), phases)
    assert not [v for v in validate_plan(spec_example, plan, holding="bottle") if v.startswith("rule 7")]
    phases = (replace(start, holding="bottle", objects={"bottle": (2.0, 0.0)}),)
    plan = Plan(spec_example.name, "feasible", cost(phases), phases)
    assert (
        "rule 7 (held object): phase 0 holding 'bottle': it is at [2.000, 0.000], [2.000, 0.000] ahead/left of the "
        "base, within no posture's ranges"
    ) in validate_plan(spec_example, plan, holding="bottle")


# ---------------------------------------------------------------------- rule 8
def test_rule8_the_hand_plan_objective_is_its_task_cost(spec_example, hand_plan):
    assert pytest.approx(74.366, abs=1e-12) == HAND_OBJECTIVE
    assert task_cost(spec_example, hand_plan.phases) == pytest.approx(HAND_OBJECTIVE, rel=1e-12)


@pytest.mark.parametrize(
    ("status", "objective", "message"),
    [
        (
            "optimal",
            -1000.0,
            "rule 8 (objective): status 'optimal': the objective -1000 is not the phases' task cost recomputed, 74.366",
        ),
        (
            "optimal",
            math.nan,
            "rule 8 (objective): status 'optimal': the objective nan is not a finite number (the phases' task "
            "cost is 74.366)",
        ),
        (
            "feasible",
            math.inf,
            "rule 8 (objective): status 'feasible': the objective inf is not a finite number (the phases' task "
            "cost is 74.366)",
        ),
        (
            "optimal",
            None,
            "rule 8 (objective): status 'optimal' has a plan, so the objective must be the task cost of its phases "
            "(74.366), not null",
        ),
        (
            "optimal",
            74.366 * (1 + 3e-6),
            "rule 8 (objective): status 'optimal': the objective 74.3662 is not the phases' task cost recomputed, "
            "74.366",
        ),
    ],
)
def test_rule8_a_lying_objective(spec_example, hand_plan, status, objective, message):
    """Issue 8: an objective of -1000 with status optimal, and NaN, were accepted."""
    assert validate_plan(spec_example, replace(hand_plan, status=status, objective=objective)) == [message]


def test_rule8_within_a_millionth_is_equal(spec_example, hand_plan):
    plan = replace(hand_plan, objective=HAND_OBJECTIVE * (1 + 5e-7))
    assert validate_plan(spec_example, plan) == []


def test_rule8_no_plan_no_objective(spec_example):
    plan = Plan(spec_example.name, "infeasible", -12.5, (), {"total_s": 0.1})
    assert validate_plan(spec_example, plan) == [
        "structure: the plan has no phases to check (status 'infeasible')",
        "rule 8 (objective): status 'infeasible' has no plan, so the objective must be null, not -12.5",
    ]


@settings(max_examples=100, deadline=None, derandomize=True, database=None)
@given(
    bases=st.lists(st.tuples(st.floats(-1, 6), st.floats(-1, 6)), min_size=1, max_size=6),
    at_goal=st.lists(st.booleans(), min_size=6, max_size=6),
    held=st.lists(st.booleans(), min_size=6, max_size=6),
)
def test_rule8_the_task_cost_matches_a_handmade_count(bases, at_goal, held):
    """The task cost (one function, shared by the planner, the env and the validator) agrees with handmade.cost."""
    spec_example = Scenario.load(EXAMPLE)
    phases = tuple(
        Phase(
            base,
            "+x",
            "move",
            holding="bottle" if held[k] else None,
            objects={"bottle": (4.0, 4.0) if at_goal[k] else (2.0, 2.0)},
        )
        for k, base in enumerate(bases)
    )
    assert task_cost(spec_example, phases) == pytest.approx(cost(phases), rel=1e-12, abs=1e-12)


# ---------------------------------------------------------------------- rule 9
def test_rule9_no_room_for_the_hand_behind_the_block(spec_example_dict, hand_plan):
    """A cube standing where the hand must go (south of the block) leaves no room to push it north."""
    spec_example_dict["clutter"].append({"id": "cube", "min": [4.015, 3.84], "max": [4.08, 3.895]})  # off the arm line
    scenario = Scenario.from_dict(spec_example_dict)
    phases = tuple(replace(p, clutter={**p.clutter, "cube": (4.0475, 3.8675)}) for p in hand_plan.phases)
    violations = validate_plan(scenario, with_phases(hand_plan, phases))
    assert violations == [
        "rule 9 (hand room): phase 3 push 'block': no room for the hand at the push contact [4.000, 3.880]: "
        "clutter 'cube' is there"
    ]


def test_rule9_an_object_where_the_hand_goes(spec_example_dict, hand_plan):
    spec_example_dict["objects"].append({"id": "cup", "start": [4.03, 3.86], "goal": [4.03, 3.86], "radius": 0.02})
    scenario = Scenario.from_dict(spec_example_dict)
    phases = tuple(replace(p, objects={**p.objects, "cup": (4.03, 3.86)}) for p in hand_plan.phases)
    plan = with_phases(hand_plan, phases)
    plan = replace(plan, objective=task_cost(scenario, plan.phases))  # the cup is delivered all along
    violations = validate_plan(scenario, plan)
    assert violations == [
        "rule 9 (hand room): phase 3 push 'block': no room for the hand at the push contact [4.000, 3.880]: "
        "object 'cup' is there"
    ]


def test_rule9_is_the_env_rule(spec_example_dict):
    """The validator refuses exactly what the env refuses: the same hand_blocker on the same positions."""
    import inspect

    from expert import validate
    from fetchcarry_env import rules

    assert "hand_blocker(" in inspect.getsource(validate._rule9_hand_room)
    assert "hand_blocker(" in inspect.getsource(rules._check_push)


# ---------------------------------------------------------------------- robustness
_coordinate = st.floats(min_value=-2.0, max_value=7.0, allow_nan=False)
_point = st.tuples(_coordinate, _coordinate)
_phase = st.builds(
    Phase,
    base=_point,
    heading=st.sampled_from(HEADINGS),
    action=st.sampled_from(PHASE_ACTIONS),
    target=st.sampled_from([None, "bottle", "block", "ghost"]),
    posture=st.sampled_from([None, "reach_far", "reach_near", "reach_up"]),
    holding=st.sampled_from([None, "bottle", "block"]),
    objects=st.dictionaries(st.sampled_from(["bottle", "ghost"]), _point, max_size=2),
    clutter=st.dictionaries(st.sampled_from(["block", "ghost"]), _point, max_size=2),
)


@settings(max_examples=150, deadline=None, derandomize=True, database=None)
@given(phases=st.lists(_phase, min_size=1, max_size=6), status=st.sampled_from(STATUSES))
def test_any_well_formed_plan_gets_messages_not_an_exception(phases, status):
    scenario = Scenario.load(EXAMPLE)
    violations = validate_plan(scenario, Plan(scenario.name, status, None, tuple(phases)))
    assert all(isinstance(m, str) and m.split(":")[0].startswith(("structure", "rule ")) for m in violations)


_coord = st.floats(-50.0, 50.0)


@settings(max_examples=300, deadline=None, derandomize=True, database=None)
@given(
    p=st.tuples(_coord, _coord),
    q=st.tuples(_coord, _coord),
    corner=st.tuples(_coord, _coord),
    size=st.tuples(st.floats(0.001, 5.0), st.floats(0.001, 5.0)),
    radius=st.floats(0.001, 1.0),
)
def test_rule1_pre_test_skips_only_far_blockers(p, q, corner, size, radius):
    """The pre-test that keeps rule 1 fast never skips a blocker closer than the radius."""
    from expert.validate import _far_from_segment
    from fetchcarry_env.geometry import Rect, segment_rect_distance

    rect = Rect(corner[0], corner[1], corner[0] + size[0], corner[1] + size[1])
    if _far_from_segment(p, q, rect, radius):
        assert segment_rect_distance(p, q, rect) > radius
