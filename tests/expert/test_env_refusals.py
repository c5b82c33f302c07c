"""The validator lists, apart from the format's violations, the phases the env refuses under its rules.

A hand-written plan that is valid by ``docs/plan-format.md`` (physical clearance, exact
arm line) but passes a table's corner closer than its octagon allows is flagged with its
phase; the plan stays valid and ``fetchcarry validate`` still exits 0.
"""

from __future__ import annotations

import json

from cli_run import run

from expert.plans import Phase, Plan, plan_objective
from expert.validate import env_refusals, validate_plan
from fetchcarry_env.scenario import Scenario

ROOM = {
    "format": "fetchcarry-scenario/1",
    "name": "corner-room",
    "area": {"min": [0.0, 0.0], "max": [3.0, 3.0]},
    "robot": {"start": [0.6, 2.35], "heading": "+x"},
    "tables": [{"id": "table", "min": [1.0, 1.0], "max": [2.0, 2.0], "height": 0.7}],
    "objects": [{"id": "bottle", "start": [1.8, 1.2], "goal": [1.8, 1.8]}],
}


def _plan(scenario: Scenario, past_corner: tuple[float, float]) -> Plan:
    """Start, a move to ``past_corner``, pick the bottle from the table's +x side, place it there."""
    start, goal = scenario.objects[0].start, scenario.objects[0].goal
    phases = (
        Phase((0.6, 2.35), "+x", "start", objects={"bottle": start}),
        Phase(past_corner, "+x", "move", objects={"bottle": start}),
        Phase((2.45, 1.2), "-x", "pick", "bottle", "reach_far", "bottle", {"bottle": start}),
        Phase((2.45, 1.8), "-x", "place", "bottle", "reach_far", None, {"bottle": goal}),
    )
    return Plan(scenario.name, "feasible", plan_objective(scenario, phases), phases)


def test_a_valid_plan_that_passes_a_corner_inside_its_octagon_is_flagged_with_its_phase():
    """(0.6, 2.35) -> (2.75, 2.2) clears the table's rounded corner by 3 cm, but no octagon region holds both ends."""
    scenario = Scenario.from_dict(ROOM)
    plan = _plan(scenario, (2.75, 2.2))
    assert validate_plan(scenario, plan) == []
    refused = env_refusals(scenario, plan)
    assert len(refused) == 1 and refused[0].startswith("env rules: phase 1 move") and "'table'" in refused[0]
    assert env_refusals(scenario, _plan(scenario, (2.75, 2.4))) == []  # beyond both sides: the env takes it


def test_fetchcarry_validate_prints_the_refusals_as_a_note_and_exits_0(capsys, tmp_path):
    scenario = Scenario.from_dict(ROOM)
    scenario_path, plan_path = tmp_path / "room.json", tmp_path / "room.plan.json"
    scenario_path.write_text(json.dumps(ROOM))
    _plan(scenario, (2.75, 2.2)).save(plan_path)
    code, out, _err = run(capsys, "validate", scenario_path, plan_path)
    assert code == 0 and "valid for" in out
    assert "note: the env refuses 1 phase(s)" in out and "phase 1 move" in out
    code, out, _err = run(capsys, "validate", scenario_path, plan_path, "--json")
    report = json.loads(out)
    assert code == 0 and report["valid"] and len(report["env_refusals"]) == 1
