"""The fuzz suite (issue 8, section 6): mutated scenario and plan files never crash anything.

Property-based tests (hypothesis) start from valid files (``examples/push_basic.json``
and a valid hand-written plan for it, ``push_basic.plan.json``), mutate them with
:mod:`mutations` and assert:

- ``Scenario.load`` raises only ``ScenarioError`` (and what it accepts obeys every rule);
- ``Plan.load`` raises only ``PlanFormatError``, and ``validate_plan`` returns messages;
- a plan that breaks one rule is rejected naming that rule;
- ``fetchcarry validate`` and ``fetchcarry plan`` exit 0, 1 or 2 with no traceback.

Every test is derandomized (the same examples on every run, so CI is stable) and the
whole suite takes well under a minute.
"""

from __future__ import annotations

import copy
import json
import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest
from cli_run import SAFETY_TIMEOUT_S, run
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import file_bytes, mutated, nudged, to_json_text, write_mutated

from expert.plans import Phase, Plan, PlanFormatError
from expert.validate import validate_plan
from fetchcarry_env.geometry import to_world_frame
from fetchcarry_env.scenario import Scenario, ScenarioError, check_rules

ROOT = Path(__file__).resolve().parents[2]
SCENARIO_FILE = ROOT / "examples" / "push_basic.json"
PLAN_FILE = Path(__file__).resolve().parent / "push_basic.plan.json"
VALID_SCENARIO = json.loads(SCENARIO_FILE.read_text())
VALID_PLAN = json.loads(PLAN_FILE.read_text())


def fuzz(examples: int) -> settings:
    """Deterministic settings (the same examples on every run) with ``examples`` examples."""
    return settings(
        max_examples=examples,
        derandomize=True,
        database=None,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.function_scoped_fixture],
    )


def write(tmp_path: Path, name: str, content: bytes) -> Path:
    path = tmp_path / name
    path.write_bytes(content)
    return path


def assert_short_and_printable(message: str, limit: int) -> None:
    """``message`` encodes as UTF-8 (no lone surrogate), has no terminal escape and is under ``limit`` characters."""
    message.encode("utf-8")
    assert "\x1b" not in message and len(message) < limit, message


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


# ---------------------------------------------------------------------- the scenario loader
@fuzz(200)
@given(data=st.data())
def test_the_scenario_loader_raises_only_scenario_error(workdir, data):
    path = write_mutated(data, workdir / "scenario.json", VALID_SCENARIO)
    try:
        scenario = Scenario.load(path)
    except ScenarioError as error:
        assert error.violations and all(isinstance(v, str) for v in error.violations)
        assert_short_and_printable(str(error), 20_000)
        assert all(v.startswith(("format:", "rule ")) for v in error.violations), error.violations
    else:
        assert check_rules(scenario) == []
        assert Scenario.from_dict(scenario.to_dict()) == scenario


# ---------------------------------------------------------------------- the plan reader and the validator
SCENARIO = Scenario.load(SCENARIO_FILE)


@fuzz(200)
@given(data=st.data())
def test_plan_load_raises_only_plan_format_error_and_the_validator_only_returns(workdir, data):
    path = write_mutated(data, workdir / "plan.json", VALID_PLAN)
    try:
        plan = Plan.load(path)
    except PlanFormatError as error:
        assert str(error).startswith(str(path)), str(error)
        assert_short_and_printable(str(error), 2_000)
        return
    violations = validate_plan(SCENARIO, plan)
    assert all(isinstance(v, str) and v.startswith(("structure", "rule ")) for v in violations), violations
    for v in violations:
        v.encode("utf-8")


_any_float = st.floats(allow_nan=False, allow_infinity=False)
_any_point = st.tuples(_any_float, _any_float)


@fuzz(150)
@given(
    phases=st.lists(
        st.builds(
            Phase,
            base=_any_point,
            heading=st.sampled_from(["+x", "+y", "-x", "-y"]),
            action=st.sampled_from(["start", "move", "pick", "place", "push"]),
            target=st.sampled_from([None, "bottle", "block"]),
            posture=st.sampled_from([None, "reach_far", "reach_near"]),
            holding=st.sampled_from([None, "bottle"]),
            objects=st.fixed_dictionaries({"bottle": _any_point}),
            clutter=st.fixed_dictionaries({"block": _any_point}),
        ),
        min_size=1,
        max_size=5,
    ),
    objective=st.one_of(st.none(), st.floats()),
)
def test_the_validator_survives_extreme_numbers(phases, objective):
    """Any finite coordinates (1e-300 to 1e308) and any objective: messages, never an exception."""
    violations = validate_plan(SCENARIO, Plan(SCENARIO.name, "feasible", objective, tuple(phases)))
    assert all(isinstance(v, str) and v.startswith(("structure", "rule ")) for v in violations)


# ---------------------------------------------------------------------- a broken rule is named
HAND = Plan.load(PLAN_FILE)
HELD = range(6, 7)  # phases that carry the bottle (picked in 5, placed in 7)
MOVES = (1, 2, 4, 6)  # phases that only move the base


def _with(plan: Plan, k: int, **changes) -> Plan:
    phases = list(plan.phases)
    phases[k] = replace(phases[k], **changes)
    return replace(plan, phases=tuple(phases))


def _shift(point, dx, dy):
    return (point[0] + dx, point[1] + dy)


offsets = st.tuples(st.floats(-3.0, 3.0), st.floats(-3.0, 3.0)).filter(lambda d: max(abs(d[0]), abs(d[1])) > 0.01)


@fuzz(150)
@given(rule=st.sampled_from([1, 2, 3, 5, 6, 7, 8]), data=st.data())
def test_a_plan_that_breaks_a_rule_is_rejected_with_it(rule, data):
    plan = HAND
    if rule == 1:  # the base disc leaves the area
        k = data.draw(st.sampled_from(MOVES))
        side = data.draw(st.sampled_from([(-1.0, None), (6.0, None), (None, -1.0), (None, 6.0)]))
        base = plan.phases[k].base
        plan = _with(
            plan, k, base=(side[0] if side[0] is not None else base[0], side[1] if side[1] is not None else base[1])
        )
    elif rule == 2:  # holding changes at a move
        k = data.draw(st.sampled_from(MOVES))
        plan = _with(plan, k, holding=None if plan.phases[k].holding else "bottle")
    elif rule == 3:  # an object that is not held moves
        k = data.draw(st.sampled_from([1, 2, 3, 4]))
        plan = _with(plan, k, objects={"bottle": _shift(plan.phases[k].objects["bottle"], *data.draw(offsets))})
    elif rule == 5:  # clutter moves outside a push
        k = data.draw(st.sampled_from([1, 2, 4, 5, 6, 7]))
        plan = _with(plan, k, clutter={"block": _shift(plan.phases[k].clutter["block"], *data.draw(offsets))})
    elif rule == 6:  # the plan stops short
        plan = replace(plan, phases=plan.phases[: data.draw(st.integers(1, len(plan.phases) - 1))])
    elif rule == 7:  # the carried bottle is not in the hand
        k = data.draw(st.sampled_from(HELD))
        plan = _with(plan, k, objects={"bottle": _shift(plan.phases[k].objects["bottle"], *data.draw(offsets))})
    elif rule == 8:  # the objective lies
        factor = data.draw(st.one_of(st.floats(-100, 100).filter(lambda f: abs(f - 1) > 1e-5), st.just(math.nan)))
        plan = replace(plan, objective=plan.objective * factor)
    assert any(v.startswith(f"rule {rule} ") for v in validate_plan(SCENARIO, plan)), (rule, plan)


@fuzz(50)
@given(heading=st.sampled_from(["+x", "+y", "-x", "-y"]), base=st.tuples(st.floats(0.5, 5.0), st.floats(0.5, 1.2)))
def test_a_carried_object_in_the_hand_breaks_no_rule_7(heading, base):
    """The converse of rule 7: wherever the base drives and turns, the bottle in the hand is fine."""
    pick = HAND.phases[5]
    dx, dy = to_world_frame(heading, 0.6, 0.0)  # picked 0.6 m straight ahead
    moved = replace(HAND.phases[6], base=base, heading=heading, objects={"bottle": (base[0] + dx, base[1] + dy)})
    plan = replace(HAND, phases=(*HAND.phases[:5], pick, moved, *HAND.phases[6:]))
    assert not [v for v in validate_plan(SCENARIO, plan) if v.startswith("rule 7")]


# ---------------------------------------------------------------------- the command line
def run_cli(capsys, *argv) -> tuple[int, str]:
    """``fetchcarry argv...`` in-process (no traceback allowed): the exit status and stderr."""
    status, _, err = run(capsys, *argv)
    return status, err


@fuzz(80)
@given(data=st.data(), which=st.sampled_from(["scenario", "plan", "both"]))
def test_fetchcarry_validate_exits_0_1_or_2_without_a_traceback(capsys, workdir, data, which):
    scenario_text, plan_text = to_json_text(VALID_SCENARIO), to_json_text(VALID_PLAN)
    if which in ("scenario", "both"):
        scenario_text = to_json_text(data.draw(mutated(VALID_SCENARIO)))
    if which in ("plan", "both"):
        plan_text = to_json_text(data.draw(mutated(VALID_PLAN)))
    scenario = write(workdir, "s.json", data.draw(file_bytes(scenario_text)))
    plan = write(workdir, "p.json", data.draw(file_bytes(plan_text)))
    status, err = run_cli(capsys, "validate", scenario, plan)
    assert status in (0, 1, 2), (status, err)
    assert "Traceback" not in err and "\x1b" not in err
    err.encode("utf-8")


@fuzz(30)
@given(data=st.data(), gentle=st.booleans())
def test_fetchcarry_plan_exits_0_1_or_2_without_a_traceback(capsys, workdir, data, gentle):
    """Hostile scenarios (exit 2) and nudged ones, often still valid, that the planner then solves (0 or 1)."""
    if gentle:
        scenario = write(workdir, "s.json", to_json_text(data.draw(nudged(VALID_SCENARIO))).encode())
    else:
        scenario = write_mutated(data, workdir / "s.json", VALID_SCENARIO, max_mutations=2)
    output = workdir / "out.plan.json"
    status, err = run_cli(capsys, "plan", scenario, "-o", output, "--time-limit", "1")
    assert status in (0, 1, 2), (status, err)
    assert "Traceback" not in err and "\x1b" not in err
    if status in (0, 1):  # a plan file was written: the validator agrees with it
        status, err = run_cli(capsys, "validate", scenario, output)
        assert status == (0 if Plan.load(output).found else 1), err


HOSTILE_FILES = {
    "utf16": json.dumps(VALID_SCENARIO).encode("utf-16"),
    "deep": b"[" * 100_000 + b"]" * 100_000,
    "huge-int": json.dumps(VALID_SCENARIO).replace('"radius": 0.22', '"radius": ' + "9" * 5000).encode(),
    "surrogate": json.dumps({**VALID_SCENARIO, "name": "bad\ud800"}).encode(),
    "obstacles": json.dumps({**VALID_SCENARIO, "obstacles": [VALID_SCENARIO["obstacles"][0]] * 20_000}).encode(),
    "room-10000-km": json.dumps({**VALID_SCENARIO, "area": {"min": [-1e7, -1e7], "max": [1e7, 1e7]}}).encode(),
    "room-1e300": json.dumps({**VALID_SCENARIO, "area": {"min": [-1e300, -1e300], "max": [1e300, 1e300]}}).encode(),
    "radius-0": json.dumps({**VALID_SCENARIO, "robot": {**VALID_SCENARIO["robot"], "radius": 0}}).encode(),
}


@pytest.mark.parametrize("command", ["validate", "plan"])
def test_hostile_scenario_files_through_the_installed_command(tmp_path, command):
    """A few cases in a real process: exit 2, one short message, no traceback, no escape codes."""
    for name, content in HOSTILE_FILES.items():
        scenario = write(tmp_path, f"{name}.json", content)
        argv = [command, str(scenario)] + (
            [str(PLAN_FILE)] if command == "validate" else ["-o", str(tmp_path / "x.json")]
        )
        done = subprocess.run(
            [sys.executable, "-m", "training.cli", *argv],
            capture_output=True,
            cwd=ROOT,
            timeout=SAFETY_TIMEOUT_S,
            check=False,
        )
        err = done.stderr.decode("utf-8", errors="replace")
        assert done.returncode == 2, (name, done.returncode, err)
        assert "Traceback" not in err and "\x1b" not in err and err.startswith("fetchcarry: "), (name, err)
        assert len(err) < 3000, (name, len(err))


def scenario_with_obstacles(count: int) -> dict:
    """The example in a 61 m room with ``count`` obstacles: posts 0.5 m wide on a 1.5 m grid, away from the rest."""
    document = copy.deepcopy(VALID_SCENARIO)
    document["area"] = {"min": [-1.0, -1.0], "max": [60.0, 60.0]}
    document["obstacles"] += [
        {
            "id": f"post_{i}",
            "min": [10 + (i % 32) * 1.5, 10 + (i // 32) * 1.5],
            "max": [10.5 + (i % 32) * 1.5, 10.5 + (i // 32) * 1.5],
        }
        for i in range(count - 1)
    ]
    return document


def test_plan_with_1000_obstacles_exits_without_a_traceback(capsys, tmp_path):
    scenario = write(tmp_path, "posts.json", json.dumps(scenario_with_obstacles(1000)).encode())
    status, err = run_cli(capsys, "plan", scenario, "-o", tmp_path / "posts.plan.json", "--time-limit", "5")
    assert status in (0, 1) and "Traceback" not in err, err


def test_validate_with_1024_obstacles(capsys, tmp_path):
    """The validator handles the most obstacles a scenario may hold (1,000 once gave a RecursionError)."""
    scenario = write(tmp_path, "posts.json", json.dumps(scenario_with_obstacles(1024)).encode())
    status, err = run_cli(capsys, "validate", scenario, PLAN_FILE)
    assert status == 0, err


def test_the_valid_files_are_valid():
    """The fuzz suite's starting points: if these broke, every mutation test would test nothing."""
    assert validate_plan(SCENARIO, HAND) == []
    assert copy.deepcopy(VALID_PLAN)["objective"] == pytest.approx(74.366)
