"""The plan file (``fetchcarry-plan/1``): round trips, unknown keys, and errors that name the field."""

from __future__ import annotations

import copy
import json
import re

import pytest
from hostile_files import write_content

from expert.plans import Plan, PlanFormatError

SPEC_EXAMPLE = {  # the plan format's reference example (as first published), verbatim
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


# ---------------------------------------------------------------------- hostile files (issue 8, section 4)
def load_error(tmp_path, content: str | bytes) -> str:
    """The PlanFormatError message of loading a file with this content (any other outcome fails)."""
    path = write_content(tmp_path / "hostile.plan.json", content)
    with pytest.raises(PlanFormatError) as info:
        Plan.load(path)
    message = str(info.value)
    assert message.startswith(str(path)) and len(message) < 1000, message
    message.encode("utf-8")  # printable: no lone surrogate in it
    return message


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        (bytes(range(256)) * 2, "not a text file: byte 128 is not UTF-8"),
        (json.dumps(SPEC_EXAMPLE).encode("utf-16"), "looks like UTF-16"),
        (json.dumps(SPEC_EXAMPLE).encode("utf-32"), "looks like UTF-16 or UTF-32"),
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
        (
            '{"format": "fetchcarry-plan/1", "status": "optimal", "phases": [{"heading": "+x", "action": "start", '
            '"base": [' + "7" * 5000 + ", 0]}]}",
            "phases[0].base must be a pair of finite numbers [x, y], got [inf, 0]",
        ),
        ("", "not valid JSON"),
        ("null", "a plan must be a JSON object"),
    ],
    ids=["binary", "utf-16", "utf-32", "deep", "5000-digits", "empty", "null"],
)
def test_hostile_files_raise_plan_format_error(tmp_path, content, expected):
    assert expected in load_error(tmp_path, content)


@pytest.mark.parametrize(
    ("data", "field"),
    [
        (_set(("objective",), 10**400), None),  # reads as inf: rule 8 of the validator refuses it
        (_set(("phases", 1, "base"), [10**400, 0]), "phases[1].base"),
        (_set(("phases", 1, "base"), [[[[[1.0]]]], 0]), "phases[1].base"),
        (_set(("scenario",), 10**5000), "'scenario' must be a string"),
        (_set(("scenario",), "basic\ud800"), "'scenario'"),
        (_set(("phases", 1, "target"), "bottle\udc00"), "phases[1].target"),
        (_set(("phases", 1, "objects"), {"\ud800": [2.0, 2.0]}), "phases[1].objects key"),
        (_set(("phases", 1, "heading"), ["+x"]), "phases[1].heading"),
        (_set(("phases", 1, "action"), {"pick": 1}), "phases[1].action"),
        (_set(("status",), ["optimal"]), "'status'"),
        (_set(("phases", 1, "objects", "\x1b[2J"), "x"), "phases[1].objects.'\\x1b[2J'"),
    ],
)
def test_hostile_values_name_the_field(data, field):
    if field is None:
        assert Plan.from_dict(data).objective == float("inf")
        return
    with pytest.raises(PlanFormatError) as info:
        Plan.from_dict(data)
    assert str(info.value).startswith(field), str(info.value)
    assert "\x1b" not in str(info.value) and len(str(info.value)) < 500
    str(info.value).encode("utf-8")


def test_a_plan_file_beyond_the_size_limit_is_not_read(tmp_path, monkeypatch):
    import expert.plans

    monkeypatch.setattr(expert.plans, "MAX_FILE_BYTES", 100)
    assert "more than the 100 a file of this kind may have" in load_error(tmp_path, " " * 101)
