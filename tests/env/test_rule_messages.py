"""A refusal's message states the values it compares as they are, and says what was given twice."""

from __future__ import annotations

import re

import pytest

from fetchcarry_env.observation import Capacity, CapacityError
from fetchcarry_env.scenario import Scenario, ScenarioError


def _scenario(table_height: float, object_height: float) -> dict:
    return {
        "format": "fetchcarry-scenario/1",
        "name": "tall",
        "area": {"min": [-1.0, -1.0], "max": [6.0, 6.0]},
        "robot": {"start": [0.0, 0.0]},
        "tables": [
            {"id": "src", "min": [1.7, 1.7], "max": [2.3, 2.3], "height": table_height},
            {"id": "dst", "min": [3.7, 3.7], "max": [4.3, 4.3], "height": 0.7},
        ],
        "objects": [{"id": "o", "start": [2.0, 2.0], "goal": [4.0, 4.0], "radius": 0.03, "height": object_height}],
    }


def test_a_height_just_over_the_headroom_prints_two_different_numbers() -> None:
    """An object 0.05 m tall on a 99.95 m table: "0.05 is more than 0.05 m" told nobody what was wrong."""
    with pytest.raises(ScenarioError) as caught:
        Scenario.from_dict(_scenario(table_height=99.95, object_height=0.05))
    message = next(v for v in caught.value.violations if "is more than" in v)
    value, limit = re.search(r"height (\S+) is more than (\S+) m", message).groups()
    assert float(value) > float(limit) and value != limit, message


def test_a_capacity_that_names_a_count_twice_is_refused() -> None:
    with pytest.raises(CapacityError, match="objects is given twice"):
        Capacity.parse("objects=3,objects=4")
    assert Capacity.parse("objects=3,clutter=4").objects == 3
