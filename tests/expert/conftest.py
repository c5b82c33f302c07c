"""Fixtures of the expert's tests."""

from __future__ import annotations

import pytest
from handmade import hand_plan_for

from expert.plans import Plan


@pytest.fixture
def hand_plan(spec_example) -> Plan:
    """A valid plan for the spec's example scenario, written by hand (7 steps)."""
    return hand_plan_for(spec_example.name)
