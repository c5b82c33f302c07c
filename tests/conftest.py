"""Shared fixtures: the spec's example scenario."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from fetchcarry_env import Scenario

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.fixture
def spec_example_dict() -> dict:
    """The scenario of docs/scenario-format.md (a fresh deep copy each time)."""
    return copy.deepcopy(json.loads((EXAMPLES / "push_basic.json").read_text()))


@pytest.fixture
def spec_example(spec_example_dict: dict) -> Scenario:
    return Scenario.from_dict(spec_example_dict)
