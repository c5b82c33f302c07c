"""The scenario model: docs/scenario-format.md read and written exactly, every rule checked with its message."""

from __future__ import annotations

import json
import math

import pytest
from hostile_files import write_content

from fetchcarry_env import Scenario, ScenarioError
from fetchcarry_env.scenario import DEFAULT_POSTURES

SPEC_COUNTS = {"objects": 64, "clutter": 256, "tables": 64, "obstacles": 1024}  # rule 6


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


# ---------------------------------------------------------------------- hostile input (issue 8, section 4)
def load_text(tmp_path, text: str | bytes) -> ScenarioError:
    """The ScenarioError of loading a file with this content (the test fails on any other outcome)."""
    path = write_content(tmp_path / "hostile.json", text)
    with pytest.raises(ScenarioError) as info:
        Scenario.load(path)
    assert str(path) in str(info.value)
    return info.value


def test_an_integer_beyond_float_range_is_rule_6(tmp_path, spec_example_dict):
    text = json.dumps(spec_example_dict).replace('"radius": 0.22', '"radius": 1' + "0" * 400)
    error = load_text(tmp_path, text)
    assert "rule 6 (numbers): robot radius is not a finite number" in error.violations
    spec_example_dict["tables"][0]["height"] = 10**400  # the same through from_dict
    assert "rule 6 (numbers): 'table_src' height is not a finite number" in violations(spec_example_dict)


def test_a_5000_digit_number_literal(tmp_path, spec_example_dict):
    text = json.dumps(spec_example_dict).replace('"height": 0.2}', '"height": ' + "9" * 5000 + "}")
    error = load_text(tmp_path, text)
    assert "rule 6 (numbers): 'bottle' height is not a finite number" in error.violations
    fraction = json.dumps(spec_example_dict).replace('"height": 0.2}', '"height": 0.' + "1" * 5000 + "}")
    path = tmp_path / "long_fraction.json"
    path.write_text(fraction)
    assert Scenario.load(path).objects[0].height == pytest.approx(0.1111111)


def test_deeply_nested_json(tmp_path, spec_example_dict):
    for depth in (100, 100_000):
        nested = "[" * depth + "]" * depth
        error = load_text(tmp_path, json.dumps(spec_example_dict)[:-1] + f', "extra": {nested}}}')
        assert len(str(error)) < 2000
        assert any("nested too deeply" in v or "unknown key 'extra'" in v for v in error.violations)


def test_postures_of_the_wrong_type(spec_example_dict):
    for value in (5, "reach_far", {"name": "x"}, None):
        spec_example_dict["robot"]["postures"] = value
        found = violations(spec_example_dict)
        assert any(v.startswith("format: robot.postures must be a list of postures") for v in found), found


@pytest.mark.parametrize(
    ("where", "value"),
    [
        (("name",), "push\ud800"),
        (("objects", 0, "id"), "bott\udfffle"),
        (("robot", "postures", 0, "name"), "\ud83d"),
    ],
)
def test_names_and_ids_must_be_valid_unicode(tmp_path, spec_example_dict, where, value):
    target = spec_example_dict
    for key in where[:-1]:
        target = target[key]
    target[where[-1]] = value
    found = violations(spec_example_dict)
    assert any("holds a lone surrogate" in v for v in found), found
    assert all("\x1b" not in v and "\u202e" not in v for v in found)
    str(ScenarioError(found)).encode("utf-8")  # printable anywhere: no lone surrogate left in the message
    error = load_text(tmp_path, json.dumps(spec_example_dict))  # the same through a file (escaped in JSON)
    assert error.violations == found


@pytest.mark.parametrize(
    "content",
    [
        bytes(range(256)) * 4,
        b"\x89PNG\r\n\x1a\n" + b"\x00" * 64,
        "utf-16",
        "utf-16-le",
        "utf-32",
        b'{"format": "fetchcarry-scenario/1"\x00}',
    ],
)
def test_binary_and_utf16_files(tmp_path, spec_example_dict, content):
    if isinstance(content, str):
        content = json.dumps(spec_example_dict).encode(content)
    error = load_text(tmp_path, content)
    assert error.violations[0].startswith(("format: not a text file", "format: not a UTF-8 text file")), (
        error.violations
    )


def test_binary_and_utf16_files_through_gym_make(tmp_path, spec_example_dict):
    import gymnasium as gym

    import fetchcarry_env  # noqa: F401  (registers the id)

    path = tmp_path / "utf16.json"
    path.write_bytes(json.dumps(spec_example_dict).encode("utf-16"))
    with pytest.raises(ScenarioError, match="not a UTF-8 text file"):
        gym.make("FetchCarryPush-v0", scenario=path)
    path.write_bytes(bytes(range(256)))
    with pytest.raises(ScenarioError, match="not a text file: byte 128 is not UTF-8"):
        gym.make("FetchCarryPush-v0", scenario=str(path))


def test_a_utf8_byte_order_mark_is_fine(tmp_path, spec_example_dict, spec_example):
    path = tmp_path / "bom.json"
    path.write_bytes(json.dumps(spec_example_dict).encode("utf-8-sig"))
    assert Scenario.load(path) == spec_example


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        (("robot", "radius"), 0, "rule 6 (numbers): robot radius 0 is less than 1 mm"),
        (("objects", 0, "radius"), 0.0, "rule 6 (numbers): 'bottle' radius 0 is less than 1 mm"),
        (("objects", 0, "height"), 0.0005, "rule 6 (numbers): 'bottle' height 0.0005 is less than 1 mm"),
        (("tables", 1, "height"), 0, "rule 6 (numbers): 'table_goal' height 0 is less than 1 mm"),
        (("clutter", 0, "height"), 0, "rule 6 (numbers): 'block' height 0 is less than 1 mm"),
        (("tables", 0, "height"), 120.0, "rule 6 (numbers): 'table_src' height 120 is more than 100 m"),
        (("objects", 0, "height"), 99.5, "rule 6 (numbers): 'bottle' height 99.5 is more than 99.3 m"),
        (("obstacles", 0, "max"), [2.8005, 3.3], "rule 6 (numbers): 'box_1' is 0.0005 x 0.4 m, less than 1 mm wide"),
        (("robot", "start"), [0.0, 1e300], "rule 6 (numbers): robot start y 1e+300 is more than 100 m from the origin"),
        (
            ("robot", "postures", 0, "forward"),
            [0.5, 150.0],
            "rule 6 (numbers): posture 'reach_far' forward range 150 is more than 100 m from the origin",
        ),
        (("objects", 0, "goal"), [math.nan, 4.0], "rule 6 (numbers): 'bottle' goal x is not a finite number"),
    ],
)
def test_rule_6_sane_sizes(spec_example_dict, path, value, message):
    target = spec_example_dict
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    assert message in violations(spec_example_dict)


@pytest.mark.parametrize("size", [1e7, 1e300])
def test_huge_rooms_are_refused(spec_example_dict, size):
    """A room of 10,000 km (big-M numerics gave a plan through the furniture) or 1e300 m (a SCIP error)."""
    spec_example_dict["area"] = {"min": [-size, -size], "max": [size, size]}
    found = violations(spec_example_dict)
    assert f"rule 6 (numbers): area min x {-size:g} is more than 100 m from the origin" in found
    assert all(v.startswith("rule 6") for v in found), found


def test_coordinates_within_100_m_are_fine(spec_example_dict):
    spec_example_dict["area"] = {"min": [-100, -100], "max": [100, 100]}
    assert Scenario.from_dict(spec_example_dict).area.max_x == 100


@pytest.mark.parametrize(
    ("key", "count"), [("obstacles", 1025), ("objects", 65), ("clutter", 257), ("tables", 65), ("obstacles", 300_000)]
)
def test_too_many_items_are_refused_with_the_count(spec_example_dict, key, count):
    item = {"objects": {"id": "o", "start": [0, 0], "goal": [0, 0]}}.get(key, {"id": "x", "min": [0, 0], "max": [1, 1]})
    spec_example_dict[key] = [item] * count
    assert violations(spec_example_dict) == [
        f"rule 6 (numbers): {count:,} {key}, more than the {SPEC_COUNTS[key]:,} a scenario may hold"
    ]


def test_the_limits_themselves_are_fine(spec_example_dict):
    """1,024 obstacles (a RecursionError once) and 256 pieces of clutter load and validate."""
    spec_example_dict["area"] = {"min": [-1.0, -1.0], "max": [60.0, 60.0]}
    spec_example_dict["obstacles"] += [
        {
            "id": f"post_{i}",
            "min": [10 + (i % 32) * 1.5, 10 + (i // 32) * 1.5],
            "max": [10.5 + (i % 32) * 1.5, 10.5 + (i // 32) * 1.5],
        }
        for i in range(1023)
    ]
    spec_example_dict["tables"].append({"id": "long", "min": [0.0, 5.0], "max": [52.0, 5.5]})
    spec_example_dict["clutter"] += [
        {"id": f"c{i}", "min": [0.1 + 0.2 * i, 5.1], "max": [0.15 + 0.2 * i, 5.2]} for i in range(255)
    ]
    scenario = Scenario.from_dict(spec_example_dict)
    assert (len(scenario.obstacles), len(scenario.clutter)) == (1024, 256)


def test_a_30_mb_file_is_refused_by_its_count_before_it_is_parsed(tmp_path, spec_example_dict, monkeypatch):
    """300,000 obstacles (30 MB): refused by their count; parsing and checking them once took a minute.

    What makes the refusal fast is that no obstacle is parsed: asserted here, not a time (which a
    loaded machine stretches); ``python tests/fuzz/campaign.py --timings`` prints the time.
    """
    import fetchcarry_env.scenario as scenario_module

    def parsed(*args, **kwargs):
        raise AssertionError("the scenario was parsed")

    spec_example_dict["obstacles"] = [
        {"id": f"box_{i}", "min": [1.0 + i * 1e-6, 1.0], "max": [1.5, 1.5]} for i in range(300_000)
    ]
    path = tmp_path / "big.json"
    path.write_text(json.dumps(spec_example_dict, indent=1))
    assert path.stat().st_size > 30e6
    monkeypatch.setattr(scenario_module._Parser, "parse", parsed)
    with pytest.raises(ScenarioError) as info:
        Scenario.load(path)
    assert info.value.violations == ["rule 6 (numbers): 300,000 obstacles, more than the 1,024 a scenario may hold"]


def test_a_file_beyond_the_size_limit_is_not_read(tmp_path, monkeypatch):
    import fetchcarry_env.scenario as scenario_module

    monkeypatch.setattr(scenario_module, "MAX_FILE_BYTES", 1000)
    error = load_text(tmp_path, " " * 1001)
    assert error.violations == ["format: the file is 1,001 bytes, more than the 1,000 a file of this kind may have"]


def test_long_and_deep_values_are_cut_in_messages(spec_example_dict):
    spec_example_dict["robot"]["start"] = list(range(100_000))
    spec_example_dict["robot"]["heading"] = [[[[[["+x"]]]]]]
    spec_example_dict["format"] = "x" * 1_000_000
    message = str(ScenarioError(violations(spec_example_dict)))
    assert len(message) < 1000, message


def test_many_unknown_keys_are_summed_up(spec_example_dict):
    spec_example_dict.update({f"k{i}": i for i in range(10_000)})
    found = violations(spec_example_dict)
    assert len(found) == 11 and found[-1] == "format: 9,990 more unknown keys in scenario"


def test_a_long_list_of_violations_is_cut_in_the_message(spec_example_dict):
    spec_example_dict["obstacles"] = [{"id": f"b{i}", "min": [9, 9], "max": [9.5, 9.5]} for i in range(200)]
    with pytest.raises(ScenarioError) as info:
        Scenario.from_dict(spec_example_dict)
    assert len(info.value.violations) == 200
    assert str(info.value).endswith("... and 150 more")


# ---------------------------------------------------------------------- rule 6 through the env
def test_a_scenario_at_the_100_m_bound_gives_observations_in_the_space(spec_example_dict):
    """Coordinates up to 100 m (the observation's bound) stay inside observation_space; beyond is refused."""
    import gymnasium as gym

    import fetchcarry_env  # noqa: F401  (registers the id)

    spec_example_dict["area"] = {"min": [-100.0, -100.0], "max": [100.0, 100.0]}
    spec_example_dict["robot"]["start"] = [-99.7, 99.7]
    spec_example_dict["tables"][1]["height"] = 99.0
    spec_example_dict["objects"][0]["height"] = 0.9
    env = gym.make("FetchCarryPush-v0", scenario=spec_example_dict, resolution=0.5)
    observation, _ = env.reset(seed=0)
    assert env.observation_space.contains(observation)
    env.close()
    spec_example_dict["area"]["max"] = [100.5, 100.0]
    with pytest.raises(ScenarioError, match=r"area max x 100\.5 is more than 100 m from the origin"):
        gym.make("FetchCarryPush-v0", scenario=spec_example_dict)


@pytest.mark.parametrize(("where", "key"), [("robot", "radius"), ("objects", "radius")])
def test_a_radius_of_zero_is_refused_before_the_simulator(spec_example_dict, where, key):
    """Radius 0 was accepted by the loader and ended in ``pybullet.error`` at reset."""
    import gymnasium as gym

    import fetchcarry_env  # noqa: F401

    target = spec_example_dict[where] if where == "robot" else spec_example_dict[where][0]
    target[key] = 0
    with pytest.raises(ScenarioError, match="radius 0 is less than 1 mm"):
        gym.make("FetchCarryPush-v0", scenario=spec_example_dict)
