"""Every exact reduction keeps the optimum: the planner's plans match optima recorded before them.

The optima in ``data/recorded_optima.json`` were made by the planner without the
fewest-phases cuts, the union and order windows and the bound on Eq. 1 per pose box
(``optima_cases.py`` says how); the
plans made now with that model under the paper's rule (``extra_phases=0``: the fewest
phases) must have the same status, number of phases and Eq. 1, and pass the validator.
Over every phase count (the default), a plan never costs more than that.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from optima_cases import recorded_cases

from expert.planner import plan
from expert.plans import eq1_value
from expert.validate import validate_plan

RECORDED = json.loads((Path(__file__).parent / "data" / "recorded_optima.json").read_text())
CASES = recorded_cases()


def test_every_case_has_a_recorded_optimum():
    assert sorted(s.name for s in CASES) == sorted(RECORDED)


@pytest.mark.parametrize("scenario", CASES, ids=[s.name for s in CASES])
def test_same_optimum_as_recorded(scenario):
    expected = RECORDED[scenario.name]
    result = plan(scenario, time_limit=120.0, extra_phases=0)
    assert result.status == expected["status"] == "optimal"
    assert len(result.phases) == expected["phases"]
    assert eq1_value(scenario, result.phases, len(result.phases)) == pytest.approx(expected["objective"], abs=1e-6)
    assert validate_plan(scenario, result) == []
    every_count = plan(scenario, time_limit=120.0)
    assert every_count.status == "optimal" and every_count.objective <= result.objective + 1e-6
