"""The plan file (``fetchcarry-plan/1``): round trips, unknown keys, and errors that name the field."""

from __future__ import annotations

import copy
import json
import re

import pytest

from expert.plans import Plan, PlanFormatError

SPEC_EXAMPLE = {  # spec/plan.md's example, verbatim
    "format": "fetchcarry-plan/1",
    "scenario": "basic-area3-07",
    "status": "optimal",
    "objective": -7.61,
    "phases": [
        {
            "base": [0.0, 0.0],
            "heading": "+x",
            "action": "start",
            "target": None,
            "posture": None,
            "holding": None,
            "objects": {"bottle": [2.0, 2.0]},
            "clutter": {"block": [4.0, 4.0]},
        },
        {
            "base": [1.42, 2.0],
            "heading": "+x",
            "action": "pick",
            "target": "bottle",
            "posture": "reach_far",
            "holding": "bottle",
            "objects": {"bottle": [2.0, 2.0]},
            "clutter": {"block": [4.0, 4.0]},
        },
        {
            "base": [3.0, 3.4],
            "heading": "+y",
            "action": "move",
            "target": None,
            "posture": None,
            "holding": "bottle",
            "objects": {"bottle": [3.0, 3.98]},
            "clutter": {"block": [4.0, 4.0]},
        },
    ],
    "stats": {"solver": "SCIP 10.0.0", "phases_tried": [3, 4, 5], "build_s": 0.006, "solve_s": 0.011, "total_s": 0.019},
}


def spec_example() -> dict:
    return copy.deepcopy(SPEC_EXAMPLE)


def test_the_spec_example_reads_as_written():
    plan = Plan.from_dict(spec_example())
    assert (plan.scenario, plan.status, plan.objective, len(plan.phases)) == ("basic-area3-07", "optimal", -7.61, 3)
    pick = plan.phases[1]
    assert (pick.base, pick.heading, pick.action, pick.target, pick.posture, pick.holding) == (
        (1.42, 2.0),
        "+x",
        "pick",
        "bottle",
        "reach_far",
        "bottle",
    )
    assert plan.phases[2].objects == {"bottle": (3.0, 3.98)}
    assert plan.stats["phases_tried"] == [3, 4, 5]
    assert plan.found  # optimal, with phases: a plan to execute


def test_the_spec_example_round_trips_through_a_file(tmp_path):
    plan = Plan.from_dict(spec_example())
    assert plan.to_dict() == SPEC_EXAMPLE
    path = tmp_path / "plan.json"
    plan.save(path)
    assert json.loads(path.read_text()) == SPEC_EXAMPLE
    assert Plan.load(path) == plan


def test_a_hand_written_plan_round_trips(tmp_path, hand_plan):
    path = tmp_path / "hand.plan.json"
    hand_plan.save(path)
    assert Plan.load(path) == hand_plan


def test_unknown_keys_are_ignored_everywhere():
    data = spec_example()
    data["solver_log"] = ["presolve", "branch"]
    data["phases"][1]["end_effector"] = [2.0, 2.0, 0.8]
    data["phases"][2]["cost"] = {"travel": 3.1}
    assert Plan.from_dict(data) == Plan.from_dict(spec_example())


def test_a_plan_without_phases_reads():
    plan = Plan.from_dict({"format": "fetchcarry-plan/1", "status": "infeasible", "objective": None, "phases": []})
    assert plan.phases == () and not plan.found


def _set(path: tuple, value):
    data = spec_example()
    target = data
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    return data


@pytest.mark.parametrize(
    ("data", "field"),
    [
        (_set(("format",), "fetchcarry-plan/2"), "'format'"),
        (_set(("status",), "done"), "'status'"),
        (_set(("objective",), "low"), "'objective'"),
        (_set(("phases",), {"0": {}}), "'phases'"),
        (_set(("stats",), [1, 2]), "'stats'"),
        (_set(("phases", 1, "heading"), "north"), "phases[1].heading"),
        (_set(("phases", 2, "action"), "fly"), "phases[2].action"),
        (_set(("phases", 0, "base"), [1.0]), "phases[0].base"),
        (_set(("phases", 1, "base"), [1.0, float("nan")]), "phases[1].base"),
        (_set(("phases", 1, "target"), 3), "phases[1].target"),
        (_set(("phases", 1, "posture"), ["reach_far"]), "phases[1].posture"),
        (_set(("phases", 2, "holding"), True), "phases[2].holding"),
        (_set(("phases", 2, "objects"), [[3.0, 3.98]]), "phases[2].objects"),
        (_set(("phases", 2, "objects", "bottle"), "here"), "phases[2].objects.bottle"),
        (_set(("phases", 0, "clutter", "block"), [4.0, "4"]), "phases[0].clutter.block"),
        (_set(("phases", 1), "pick"), "phases[1]"),
    ],
)
def test_format_errors_name_the_field(data, field):
    with pytest.raises(PlanFormatError, match=r"^" + re.escape(field)):
        Plan.from_dict(data)


def test_a_file_that_is_not_json_names_the_file(tmp_path):
    path = tmp_path / "broken.plan.json"
    path.write_text('{"format": "fetchcarry-plan/1",')
    with pytest.raises(PlanFormatError, match=r"broken\.plan\.json: not valid JSON"):
        Plan.load(path)


def test_a_file_error_names_the_file_and_the_field(tmp_path):
    path = tmp_path / "bad.plan.json"
    path.write_text(json.dumps(_set(("phases", 1, "heading"), "north")))
    with pytest.raises(PlanFormatError, match=r"bad\.plan\.json: phases\[1\]\.heading must be one of"):
        Plan.load(path)


def test_a_produced_plan_round_trips(tmp_path, spec_example):
    from expert.planner import plan

    produced = plan(spec_example, time_limit=20.0)
    assert produced.found
    path = tmp_path / "produced.plan.json"
    produced.save(path)
    assert Plan.load(path) == produced
    assert Plan.from_dict(json.loads(json.dumps(produced.to_dict()))) == produced
