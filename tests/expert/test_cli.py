"""``fetchcarry plan`` and ``fetchcarry validate``: exit statuses 0/1/2 and messages, never a traceback.

Run in-process through ``training.cli.main`` (fast); one test runs the installed
console script in a subprocess.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from cli_run import run

from expert.plans import Plan
from expert.validate import validate_plan
from fetchcarry_env.scenario import Scenario

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"


@pytest.fixture
def plan_file(tmp_path, hand_plan) -> Path:
    path = tmp_path / "hand.plan.json"
    hand_plan.save(path)
    return path


@pytest.fixture
def bad_inputs(tmp_path) -> dict[str, Path]:
    """Files that are bad input for both commands, by what is wrong with them."""
    broken = tmp_path / "broken.json"
    broken.write_text('{"format": "fetchcarry-scenario/1", "name": ')
    invalid = json.loads(EXAMPLE.read_text())
    invalid["objects"][0]["goal"] = [5.0, 5.0]  # on no table: rule 4 of docs/scenario-format.md
    invalid["obstacles"][0]["id"] = "table_src"  # a duplicate id: rule 1
    invalid_path = tmp_path / "invalid.json"
    invalid_path.write_text(json.dumps(invalid))
    binary = tmp_path / "binary.json"
    binary.write_bytes(bytes(range(256)))
    return {"missing": tmp_path / "nope.json", "broken": broken, "invalid": invalid_path, "binary": binary}


# ---------------------------------------------------------------------- validate
def test_validate_a_valid_plan(capsys, plan_file):
    status, out, err = run(capsys, "validate", EXAMPLE, plan_file)
    assert status == 0, err
    assert "valid for" in out and "8 phases (the start and 7 steps)" in out


def test_validate_lists_every_violation(capsys, tmp_path, hand_plan):
    from handmade import with_phase

    broken = with_phase(with_phase(hand_plan, 1, base=(4.0, -0.9)), 5, base=(2.8, 2.0))
    path = tmp_path / "broken.plan.json"
    broken.save(path)
    status, out, _ = run(capsys, "validate", EXAMPLE, path)
    assert status == 1
    assert "INVALID" in out and "2 violation(s)" in out
    assert "rule 1 (area): phase 1" in out and "rule 4 (reach): phase 5 pick 'bottle' is 0.800 m ahead" in out
    status, out, _ = run(capsys, "validate", "--json", EXAMPLE, path)
    report = json.loads(out)
    assert status == 1 and report["valid"] is False and len(report["violations"]) == 2


def test_validate_json_for_a_valid_plan(capsys, plan_file):
    status, out, _ = run(capsys, "validate", EXAMPLE, plan_file, "--json")
    assert status == 0 and json.loads(out) == {
        "scenario": str(EXAMPLE),
        "plan": str(plan_file),
        "valid": True,
        "violations": [],
        "env_refusals": [],  # the phases the env's rules refuse: notes, not violations
    }


@pytest.mark.parametrize(
    ("which", "message"),
    [
        ("missing", "scenario file not found: "),
        ("broken", "not valid JSON"),
        ("invalid", "rule 4 (on a table): object 'bottle' goal [5.0, 5.0] is not fully on a table"),
        ("binary", "not a text file"),
    ],
)
def test_validate_a_bad_scenario_is_exit_2(capsys, bad_inputs, plan_file, which, message):
    status, out, err = run(capsys, "validate", bad_inputs[which], plan_file)
    assert status == 2
    assert message in err and err.startswith("fetchcarry: ") and out == ""


def test_validate_an_invalid_scenario_lists_every_rule_it_breaks(capsys, bad_inputs, plan_file):
    _, _, err = run(capsys, "validate", bad_inputs["invalid"], plan_file)
    assert "rule 1 (unique ids): id 'table_src' is used more than once" in err
    assert "rule 4 (on a table)" in err


@pytest.mark.parametrize(
    ("which", "message"),
    [
        ("missing", "plan file not found: "),
        ("broken", "broken.json: not valid JSON"),
        ("binary", "binary.json: not a text file"),
    ],
)
def test_validate_a_bad_plan_file_is_exit_2(capsys, bad_inputs, which, message):
    status, _, err = run(capsys, "validate", EXAMPLE, bad_inputs[which])
    assert status == 2 and message in err


def test_validate_a_plan_in_the_wrong_format_is_exit_2(capsys, tmp_path, hand_plan):
    data = hand_plan.to_dict()
    data["phases"][3]["heading"] = "north"
    path = tmp_path / "wrong.plan.json"
    path.write_text(json.dumps(data))
    status, _, err = run(capsys, "validate", EXAMPLE, path)
    assert status == 2 and "phases[3].heading must be one of +x, +y, -x, -y, got 'north'" in err


def test_validate_a_directory_is_exit_2(capsys, tmp_path, plan_file):
    status, _, err = run(capsys, "validate", tmp_path, plan_file)
    assert status == 2 and "is a directory" in err


@pytest.mark.parametrize(
    "argv",
    [
        ("validate", EXAMPLE, "x.json", "--strict"),
        ("validate",),  # validate SCENARIO alone checks the scenario (below)
        ("validate", EXAMPLE, "x.json", "y.json"),
        ("plan", EXAMPLE, "--time-limit", "soon"),
        ("plan", EXAMPLE, "--time-limit", "-1"),
        ("plan", EXAMPLE, "--max-phases", "0"),
        ("plan", EXAMPLE, "--frobnicate"),
    ],
)
def test_usage_errors_are_exit_2(capsys, argv):
    status, out, err = run(capsys, *argv)
    assert status == 2 and "usage: fetchcarry" in err and "error:" in err and out == ""


# ---------------------------------------------------------------------- plan: bad input (before planning)
@pytest.mark.parametrize(
    ("which", "message"),
    [
        ("missing", "scenario file not found: "),
        ("broken", "not valid JSON"),
        ("invalid", "rule 1 (unique ids)"),
    ],
)
def test_plan_bad_scenario_is_exit_2(capsys, tmp_path, bad_inputs, which, message):
    output = tmp_path / "out.plan.json"
    status, out, err = run(capsys, "plan", bad_inputs[which], "-o", output)
    assert status == 2 and message in err and out == ""
    assert not output.exists()


def test_plan_into_a_missing_directory_is_exit_2(capsys, tmp_path):
    status, _, err = run(capsys, "plan", EXAMPLE, "-o", tmp_path / "no" / "such" / "dir" / "p.json")
    assert status == 2 and "does not exist" in err


def test_plot_into_an_unknown_picture_format_is_exit_2(capsys, tmp_path):
    status, _, err = run(capsys, "plan", EXAMPLE, "-o", tmp_path / "p.json", "--plot", tmp_path / "plan.xyz")
    assert status == 2 and "cannot draw into" in err and ".png" in err
    assert not (tmp_path / "p.json").exists()  # refused before planning


def test_help_explains_the_exit_statuses(capsys):
    for command in ("plan", "validate"):
        status, out, _ = run(capsys, command, "--help")
        text = " ".join(out.split())  # argparse wraps lines at the terminal width
        assert status == 0 and "Exit status: 0" in text and "2 bad input" in text


# ---------------------------------------------------------------------- plan: with the planner
def test_plan_finds_writes_and_draws_a_valid_plan(capsys, tmp_path):
    output, picture = tmp_path / "p.plan.json", tmp_path / "p.png"
    status, out, err = run(capsys, "plan", EXAMPLE, "-o", output, "--plot", picture, "--time-limit", "20")
    assert status == 0, err
    assert "warning" not in err  # the command validates its own plan
    plan = Plan.load(output)
    assert plan.status in ("optimal", "feasible") and plan.found
    assert validate_plan(Scenario.load(EXAMPLE), plan) == []
    assert f"status     {plan.status}" in out and f"plan written to {output}" in out
    assert " push " in out and " place " in out  # the phase table
    assert picture.read_bytes()[:4] == b"\x89PNG"


def test_plan_json_summary_and_output(capsys, tmp_path):
    output = tmp_path / "push_basic.plan.json"
    status, out, _ = run(capsys, "plan", EXAMPLE, "--json", "-o", output)
    summary = json.loads(out)
    assert status == 0 and summary["found"] and summary["plan_path"] == str(output)
    assert summary["violations"] == [] and Plan.load(output).to_dict()["phases"] == summary["phases"]


def test_plan_without_output_writes_no_file(capsys, tmp_path, monkeypatch):
    """A new user's ``fetchcarry plan SCENARIO`` left a plan file in the current folder; only ``-o`` writes one."""
    monkeypatch.chdir(tmp_path)
    status, out, err = run(capsys, "plan", EXAMPLE)
    assert status == 0, err
    assert list(tmp_path.iterdir()) == []
    assert "plan not written (-o PLAN writes it)" in out and " place " in out
    status, out, _ = run(capsys, "plan", EXAMPLE, "--json")
    assert status == 0 and json.loads(out)["plan_path"] is None and list(tmp_path.iterdir()) == []


def infeasible_scenario(path: Path) -> Path:
    """The spec example with the source table walled in: the robot cannot come within reach of the bottle."""
    data = json.loads(EXAMPLE.read_text())
    data["obstacles"] += [
        {"id": "wall_s", "min": [1.3, 1.3], "max": [2.7, 1.4]},
        {"id": "wall_n", "min": [1.3, 2.6], "max": [2.7, 2.7]},
        {"id": "wall_w", "min": [1.3, 1.4], "max": [1.4, 2.6]},
        {"id": "wall_e", "min": [2.6, 1.4], "max": [2.7, 2.6]},
    ]
    Scenario.from_dict(data)  # a valid scenario: the trouble is only that it has no plan
    path.write_text(json.dumps(data))
    return path


def test_plan_an_infeasible_scenario_is_exit_1(capsys, tmp_path):
    scenario = infeasible_scenario(tmp_path / "walled.json")
    output = tmp_path / "walled.plan.json"
    status, out, err = run(capsys, "plan", scenario, "-o", output, "--max-phases", "5", "--time-limit", "20")
    assert status == 1, err
    plan = Plan.load(output)
    assert plan.status in ("infeasible", "time_limit") and not plan.phases
    assert f"status     {plan.status}" in out


# ---------------------------------------------------------------------- the console script
def test_the_console_script_reports_bad_input_without_a_traceback(tmp_path, plan_file):
    script = shutil.which("fetchcarry") or pytest.fail("the fetchcarry console script is not installed")
    missing = subprocess.run(
        [script, "validate", str(tmp_path / "nope.json"), str(plan_file)], capture_output=True, text=True, timeout=60
    )
    assert missing.returncode == 2 and "scenario file not found" in missing.stderr
    assert "Traceback" not in missing.stderr
    valid = subprocess.run(
        [sys.executable, "-m", "training.cli", "validate", str(EXAMPLE), str(plan_file)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert valid.returncode == 0, valid.stderr


def test_plan_with_extra_phases_says_which_optimality_it_proves(capsys, tmp_path):
    """By default the least task cost over every phase count; ``--extra-phases K`` up to N + K phases, 0 the
    paper's rule; the summary says what ``optimal`` then means."""
    output = tmp_path / "plan.json"
    status, every, _ = run(capsys, "plan", str(EXAMPLE), "-o", str(output))
    assert status == 0 and "whatever their number of phases" in every
    status, fewest, _ = run(capsys, "plan", str(EXAMPLE), "-o", str(output), "--extra-phases", "0")
    assert status == 0 and "among the plans with the fewest phases" in fewest
    status, out, _ = run(capsys, "plan", str(EXAMPLE), "-o", str(output), "--extra-phases", "2")
    assert status == 0 and "at most N + 2 phases" in out
    result = Plan.load(output)
    assert validate_plan(Scenario.load(EXAMPLE), result) == []
    assert max(result.stats["phases_tried"]) <= result.stats["fewest_phases"] + 2
    status, _, err = run(capsys, "plan", str(EXAMPLE), "-o", str(output), "--extra-phases", "-1")
    assert status == 2 and "--extra-phases" in err


@pytest.mark.parametrize(("gap", "says"), [(0.0123, "(proven gap 1.2%)"), (None, "(no proven gap")])
def test_a_feasible_plan_says_its_proven_gap_or_that_it_has_none(gap, says):
    """A time-limited plan states its proven gap, or says that no bound covers it (the decoupled plan)."""
    from expert.planner import plan
    from training.cli.planning import _plan_summary_text

    found = plan(Scenario.load(EXAMPLE))
    feasible = Plan(found.scenario, "feasible", found.objective, found.phases, {**found.stats, "gap": gap})
    text = _plan_summary_text(EXAMPLE, feasible, Path("plan.json"), None, 10.0)
    assert says in text


def test_the_optimality_sentence_says_only_what_holds(capsys, tmp_path):
    """An infeasible scenario claimed "optimal ... among the plans with the fewest phases"; so did ``feasible``."""
    import numpy as np

    from expert.planner import optimality, plan
    from fetchcarry_env.families import get_family

    output = tmp_path / "walled.plan.json"
    status, out, _ = run(capsys, "plan", infeasible_scenario(tmp_path / "walled.json"), "-o", output,
                         "--max-phases", "5", "--json")  # fmt: skip
    stats = json.loads(out)["stats"]
    assert status == 1 and "optimal for" not in stats["optimality"] and "no claim of optimality" in stats["optimality"]
    assert Plan.load(output).stats["optimality"] == stats["optimality"]
    feasible = optimality(0, "feasible", {"stopped_by": "node_limit"})
    assert feasible.startswith("not proven optimal: the node budget ran out") and "fewest phases" in feasible
    assert "safety stop" in optimality(None, "feasible", {"stopped_by": "clock"})
    result = plan(get_family("multi-4").sample(np.random.default_rng(1)), node_limit=1)  # any status may come
    assert result.stats["optimality"] == optimality(None, result.status, result.stats)
    assert result.stats["optimality"].startswith("optimal for") == (result.status == "optimal")


# ---------------------------------------------------------------------- validate SCENARIO (no plan)
def test_validate_a_scenario_alone_without_planning(capsys, tmp_path, bad_inputs, monkeypatch):
    """No command checked a scenario alone or drew it without planning: ``validate SCENARIO [--plot PNG]``."""
    import expert.planner

    monkeypatch.setattr(expert.planner, "plan", lambda *a, **k: pytest.fail("validate SCENARIO must not plan"))
    picture = tmp_path / "scenario.png"
    status, out, err = run(capsys, "validate", EXAMPLE, "--plot", picture)
    assert status == 0, err
    assert "valid scenario basic-area3-07 (1 object(s), 2 table(s)" in out and f"plot written to {picture}" in out
    assert picture.read_bytes()[:4] == b"\x89PNG"
    status, out, err = run(capsys, "validate", bad_inputs["invalid"], "--json", "--plot", tmp_path / "bad.png")
    report = json.loads(out)
    assert status == 1 and not report["valid"] and len(report["violations"]) == 2, err
    assert any(v.startswith("rule 1 (unique ids)") for v in report["violations"]) and "not drawn" in err
    assert not (tmp_path / "bad.png").exists()
    for which in ("missing", "broken", "binary"):
        assert run(capsys, "validate", bad_inputs[which])[0] == 2, which
    status, _, err = run(capsys, "validate", Path(__file__).parents[1] / "fuzz" / "push_basic.plan.json")
    assert status == 2 and "is a plan" in err
    status, _, err = run(capsys, "validate", EXAMPLE, "--plot", tmp_path / "scenario.xyz")
    assert status == 2 and "cannot draw into" in err


def test_validate_with_a_plan_can_draw_it(capsys, tmp_path, plan_file):
    picture = tmp_path / "plan.png"
    status, out, _ = run(capsys, "validate", EXAMPLE, plan_file, "--plot", picture)
    assert status == 0 and f"{plan_file}: valid for {EXAMPLE}" in out and picture.read_bytes()[:4] == b"\x89PNG"
