"""The examples of docs/scenario-format.md and docs/plan-format.md are what they say they are."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from expert.plans import Plan
from expert.validate import validate_plan
from fetchcarry_env.scenario import Scenario

DOCS = Path(__file__).resolve().parents[1] / "docs"


def json_blocks(name: str) -> list:
    return [json.loads(block) for block in re.findall(r"```json\n(.*?)```", (DOCS / name).read_text(), re.S)]


def test_every_scenario_example_is_valid():
    examples = json_blocks("scenario-format.md")
    assert len(examples) == 2
    scenarios = [Scenario.from_dict(example) for example in examples]
    examples_dir = DOCS.parent / "examples"
    assert scenarios[1] == Scenario.load(examples_dir / "push_basic.json")


def test_the_plan_example_is_valid_for_the_small_scenario():
    small = Scenario.from_dict(json_blocks("scenario-format.md")[0])
    (example,) = json_blocks("plan-format.md")
    plan = Plan.from_dict(example)
    assert validate_plan(small, plan) == []
    assert plan.objective == pytest.approx(1.955 + 1.7 + 10)  # the travel and the one phase the cup waits


def test_the_planner_agrees_with_the_plan_example():
    from expert.planner import plan

    small = Scenario.from_dict(json_blocks("scenario-format.md")[0])
    result = plan(small, time_limit=20.0)
    assert result.status == "optimal" and len(result.phases) == 3
    assert result.objective == pytest.approx(13.655, abs=1e-9)


@pytest.mark.parametrize("name", ["scenario-format.md", "plan-format.md"])
def test_the_format_docs_name_every_rule(name):
    text = (DOCS / name).read_text()
    rules = 6 if name == "scenario-format.md" else 9
    for number in range(1, rules + 1):
        assert re.search(rf"^{number}\. \*\*", text, re.M), number
