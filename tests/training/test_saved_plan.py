"""``fetchcarry rollout --plan PLAN --scenario S``: a saved plan executed in the env; one wording of a plan's length."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_run import run

from expert.plans import Plan, plan_length
from training.cli.episodes import plan_status_text
from training.rollout import EpisodeFigures

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"


@pytest.fixture(scope="module")
def plan_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example's optimal plan, written by ``fetchcarry plan``."""
    from training.cli import main

    path = tmp_path_factory.mktemp("plan") / "plan.json"
    assert main(["plan", str(EXAMPLE), "-o", str(path)]) == 0
    return path


def test_a_saved_plan_executes_and_delivers(capsys, plan_file: Path) -> None:
    status, out, _ = run(capsys, "rollout", "--plan", plan_file, "--scenario", EXAMPLE)
    phases = len(Plan.load(plan_file).phases)
    assert status == 0 and "delivered: 1/1" in out and f"after {phases - 1} steps" in out
    assert "the first plan is optimal" in out and plan_length(phases) in out


def test_a_plan_that_stops_short_ends_the_episode_undelivered(capsys, plan_file: Path, tmp_path: Path) -> None:
    """The plan without its last phase (the place): the episode ends when the phases run out, exit 1."""
    data = json.loads(plan_file.read_text())
    data["phases"] = data["phases"][:-1]
    short = tmp_path / "short.json"
    short.write_text(json.dumps(data))
    status, out, _ = run(capsys, "rollout", "--plan", short, "--scenario", EXAMPLE, "--json")
    figures = json.loads(out)
    assert status == 1 and figures["outcome"] == "plan_ended" and figures["steps"] == len(data["phases"])


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d.update(phases=[], status="infeasible", objective=None), "no phases"),
        (lambda d: d["phases"][1].update(base=[0.013, 0.0]), "not a point of the lattice"),
    ],
    ids=["no-phases", "off-lattice"],
)
def test_a_plan_the_env_cannot_execute_is_bad_input(capsys, plan_file: Path, tmp_path: Path, change, message) -> None:
    data = json.loads(plan_file.read_text())
    change(data)
    broken = tmp_path / "broken.json"
    broken.write_text(json.dumps(data))
    status, _, err = run(capsys, "rollout", "--plan", broken, "--scenario", EXAMPLE)
    assert status == 2 and message in err


def test_a_saved_plan_needs_a_scenario_file(capsys, plan_file: Path) -> None:
    status, _, err = run(capsys, "rollout", "--plan", plan_file, "--family", "push")
    assert status == 2 and "--scenario" in err


def test_every_command_words_a_plans_length_the_same(capsys, plan_file: Path, tmp_path: Path) -> None:
    """``plan`` said "phases 7" where ``validate``, the plot title and ``rollout`` said "6 steps"."""
    import matplotlib

    matplotlib.use("Agg")
    from expert.plot import _title
    from fetchcarry_env.scenario import Scenario

    plan = Plan.load(plan_file)
    length = plan_length(len(plan.phases))
    _, planned, _ = run(capsys, "plan", EXAMPLE)
    _, validated, _ = run(capsys, "validate", EXAMPLE, plan_file)
    _, rolled, _ = run(capsys, "rollout", "--plan", plan_file, "--scenario", EXAMPLE)
    for text in (planned, validated, rolled, _title(Scenario.load(EXAMPLE), plan)):
        assert length in text, text


def test_rollout_says_when_a_plan_is_the_unproven_fallback() -> None:
    """The objective was printed without the plan's status, and a fallback plan looked like a proven one."""
    figures = EpisodeFigures(
        seed=0, scenario="s", objects=1, delivered=1, success=True, outcome="delivered", failure=None, steps=5,
        episode_return=1.0, path_length_m=1.0, collisions=0, invalid_actions=0, planning_s=1.0, policy_s=1.0,
        simulation_s=0.1, plans=2, replans=1, repairs=0, planner_failures=0, objective=-1.0,
        plan_status="feasible", fallback_plans=1,
    )  # fmt: skip
    text = plan_status_text(figures)
    assert "not proven optimal" in text and "1 of 2 planning call(s)" in text and "decoupled fallback" in text
