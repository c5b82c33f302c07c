"""The scenario model: spec/scenario.md read and written exactly, every rule checked with its message."""

from __future__ import annotations

import json
import math

import pytest

from fetchcarry_env import Scenario, ScenarioError
from fetchcarry_env.scenario import DEFAULT_POSTURES


def violations(data: dict) -> list[str]:
    with pytest.raises(ScenarioError) as info:
        Scenario.from_dict(data)
    return info.value.violations


def test_spec_example_round_trips(spec_example_dict, spec_example, tmp_path):
    assert spec_example.to_dict() == spec_example_dict
    path = tmp_path / "s.json"
    spec_example.save(path)
    assert Scenario.load(path) == spec_example


def test_defaults_fill_optional_fields(spec_example_dict):
    robot = spec_example_dict["robot"]
    for key in ("heading", "radius", "postures"):
        del robot[key]
    for key in ("tables", "obstacles", "clutter"):
        spec_example_dict.pop(key)
    spec_example_dict["objects"][0]["start"] = [2.0, 2.0]
    with pytest.raises(ScenarioError, match="not fully on a table"):  # no tables: the object floats
        Scenario.from_dict(spec_example_dict)


def test_default_robot(spec_example_dict):
    robot = spec_example_dict["robot"]
    for key in ("heading", "radius", "postures"):
        del robot[key]
    scenario = Scenario.from_dict(spec_example_dict)
    assert scenario.robot.heading == "+x"
    assert scenario.robot.radius == 0.22
    assert scenario.robot.postures == DEFAULT_POSTURES


def test_unknown_keys_are_named(spec_example_dict):
    spec_example_dict["colour"] = "red"
    spec_example_dict["robot"]["speed"] = 1
    spec_example_dict["tables"][0]["legs"] = 4
    found = violations(spec_example_dict)
    assert any("unknown key 'colour' in scenario" in v for v in found)
    assert any("unknown key 'speed' in robot" in v for v in found)
    assert any("unknown key 'legs' in 'table_src'" in v for v in found)


def test_wrong_format_string(spec_example_dict):
    spec_example_dict["format"] = "fetchcarry-scenario/2"
    assert any("'format' must be 'fetchcarry-scenario/1'" in v for v in violations(spec_example_dict))


def test_objects_required(spec_example_dict):
    spec_example_dict["objects"] = []
    assert any("at least one object" in v for v in violations(spec_example_dict))


def test_rule_1_unique_ids(spec_example_dict):
    spec_example_dict["obstacles"][0]["id"] = "table_src"
    assert violations(spec_example_dict) == ["rule 1 (unique ids): id 'table_src' is used more than once"]


def test_rule_2_proper_rectangles(spec_example_dict):
    spec_example_dict["obstacles"][0]["max"] = [2.7, 3.3]  # max x < min x
    assert violations(spec_example_dict) == ["rule 2 (rectangles): 'box_1' must have min < max on both axes"]


def test_rule_2_inside_area(spec_example_dict):
    spec_example_dict["obstacles"][0]["max"] = [7.0, 3.3]
    assert violations(spec_example_dict) == ["rule 2 (rectangles): 'box_1' does not lie inside the area"]


def test_rule_3_start_inside_area(spec_example_dict):
    spec_example_dict["robot"]["start"] = [-0.9, 0.0]
    assert violations(spec_example_dict) == [
        "rule 3 (robot start): the base disc at robot.start does not lie inside the area"
    ]


def test_rule_3_start_off_furniture(spec_example_dict):
    spec_example_dict["robot"]["start"] = [3.0, 2.75]
    assert violations(spec_example_dict) == ["rule 3 (robot start): the base disc at robot.start overlaps 'box_1'"]


def test_rule_4_objects_on_tables(spec_example_dict):
    spec_example_dict["objects"][0]["goal"] = [4.28, 4.0]  # disc hangs over the edge
    assert violations(spec_example_dict) == [
        "rule 4 (on a table): object 'bottle' goal [4.28, 4.0] is not fully on a table"
    ]


def test_rule_4_clutter_on_one_table(spec_example_dict):
    spec_example_dict["clutter"][0]["min"] = [4.2, 3.9]
    spec_example_dict["clutter"][0]["max"] = [4.4, 4.1]
    assert violations(spec_example_dict) == ["rule 4 (on a table): clutter 'block' is not fully on one table"]


def test_rule_5_no_overlap(spec_example_dict):
    spec_example_dict["objects"].append({"id": "cup", "start": [2.05, 2.0], "goal": [3.8, 3.8]})
    spec_example_dict["clutter"].append({"id": "lid", "min": [1.9, 2.02], "max": [2.1, 2.2], "height": 0.05})
    found = violations(spec_example_dict)
    assert "rule 5 (no overlap): objects 'bottle' and 'cup' overlap at the start" in found
    assert "rule 5 (no overlap): object 'bottle' overlaps clutter 'lid' at the start" in found
    assert "rule 5 (no overlap): object 'cup' overlaps clutter 'lid' at the start" in found


def test_rule_5_clutter_overlap(spec_example_dict):
    spec_example_dict["clutter"].append({"id": "lid", "min": [4.0, 4.0], "max": [4.2, 4.2]})
    assert violations(spec_example_dict) == ["rule 5 (no overlap): clutter 'block' and 'lid' overlap"]


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        (("objects", 0, "radius"), -0.01, "rule 6 (numbers): 'bottle' radius is negative"),
        (("tables", 0, "height"), -1.0, "rule 6 (numbers): 'table_src' height is negative"),
        (("robot", "radius"), math.inf, "rule 6 (numbers): robot radius is not a finite number"),
        (("robot", "postures", 1, "forward"), [0.5, 0.4], "posture 'reach_near' forward range has a negative width"),
    ],
)
def test_rule_6_numbers(spec_example_dict, path, value, message):
    target = spec_example_dict
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    assert any(message in v for v in violations(spec_example_dict))


def test_all_violations_reported_at_once(spec_example_dict):
    spec_example_dict["obstacles"][0]["id"] = "block"
    spec_example_dict["objects"][0]["start"] = [9.0, 9.0]
    spec_example_dict["robot"]["start"] = [3.0, 2.75]
    found = violations(spec_example_dict)
    assert {v.split(":")[0] for v in found} >= {"rule 1 (unique ids)", "rule 3 (robot start)", "rule 4 (on a table)"}


def test_wrong_types_are_named(spec_example_dict):
    spec_example_dict["objects"][0]["radius"] = "big"
    spec_example_dict["robot"]["heading"] = "north"
    found = violations(spec_example_dict)
    assert any("'bottle'.radius must be a number" in v for v in found)
    assert any("robot.heading must be one of" in v for v in found)


def test_load_reports_broken_json_and_file(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text("{ not json")
    with pytest.raises(ScenarioError, match="not valid JSON") as info:
        Scenario.load(path)
    assert str(path) in str(info.value)


def test_error_is_a_value_error(spec_example_dict):
    spec_example_dict["objects"] = "bottle"
    with pytest.raises(ValueError, match="'objects' must be a list"):
        Scenario.from_dict(spec_example_dict)


def test_json_text_round_trip(spec_example):
    assert Scenario.from_dict(json.loads(json.dumps(spec_example.to_dict()))) == spec_example
