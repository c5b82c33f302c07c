"""``fetchcarry bench planner``: a tiny run prints the tables and every plan is optimal."""

from __future__ import annotations

import io
import json
from argparse import Namespace

import pytest

from expert import bench
from fetchcarry_env.errors import UsageError
from training.cli import main as fetchcarry
from training.cli.bench import run_planner


def args(**changes) -> Namespace:
    base = {"seed": 1, "scale": 0.05, "only": ["V-B", "L"], "time_limit": 30.0, "baseline": False, "json": False}
    return Namespace(**{**base, **changes})


def test_tiny_run_prints_paper_and_goal_tables():
    out = io.StringIO()
    assert run_planner(args(), out) == 0
    text = out.getvalue()
    for expected in ("V-B area III", "IV-F L corridor", "0.22 (0.20)", "median 20, p95 50", "where the time goes"):
        assert expected in text
    assert "not optimal" not in text


def test_json_lists_every_run():
    out = io.StringIO()
    assert run_planner(args(json=True), out) == 0
    data = json.loads(out.getvalue())
    assert len(data["runs"]) == 6  # five V-B areas and the corridor, one scenario each
    assert all(r["status"] == "optimal" and r["valid"] for r in data["runs"])
    assert data["cases"]["V-B area I"]["paper"] == "0.05 (0.02)"


def test_unknown_group_is_a_usage_error():
    with pytest.raises(UsageError, match="nope"):
        run_planner(args(only=["nope"]), io.StringIO())


def test_the_command_parses_its_options(capsys):
    assert fetchcarry(["bench", "planner", "--scale", "0.05", "--only", "L", "--seed", "3"]) == 0
    assert "IV-F L corridor" in capsys.readouterr().out


def test_help_shows_no_docstring_markup(capsys):
    for what in ("planner", "env", "generate"):
        with pytest.raises(SystemExit):
            fetchcarry(["bench", what, "--help"])
        text = capsys.readouterr().out
        assert ":mod:" not in text and ":func:" not in text and "``" not in text, what


def test_scale_families_are_in_the_benchmark():
    groups = {c.group for c in bench.cases()}
    assert {"4 obj", "5 obj", "6 obj", "cov 2", "cov 3"} <= groups


@pytest.mark.parametrize("count", [2, 3])
def test_covered_scenarios_cover_every_goal(count):
    import numpy as np

    from expert import bench_cases
    from fetchcarry_env.scenario import check_rules

    scenario = bench_cases.covered(count, np.random.default_rng(count))
    assert check_rules(scenario) == [] and len(scenario.objects) == count
    for obj in scenario.objects:
        assert any(c.rect.overlaps_disc(obj.goal, obj.radius) for c in scenario.clutter), obj.id


def _anytime_record(index: int, limit: float, objective: float, phases: int = 8, **changes) -> dict:
    record = {"group": "4 obj", "index": index, "limit": limit, "reference": limit == 30.0, "status": "optimal",
              "phases": phases, "objective": objective, "gap": 0.0, "seconds": 0.05, "valid": True}  # fmt: skip
    return {**record, **changes}


def test_anytime_summary_compares_each_plan_with_its_reference():
    from expert.bench_anytime import summary

    reference = [_anytime_record(0, 30.0, 10.0), _anytime_record(1, 30.0, 20.0)]
    short = [
        _anytime_record(0, 0.1, 10.4, status="time_limit", gap=None),  # 4 % above: within 5 %
        _anytime_record(1, 0.1, 22.0, status="time_limit", gap=0.08),  # 10 % above
    ]
    lines = summary(short + reference, reference)
    row = next(line for line in lines if line.startswith("4 obj") and "0.10" in line)
    assert row.split()[3:7] == ["2/2", "0", "2", "1"]  # valid, optimal, reference's phases, within 5 %
    assert "4.00, 10.00 / 8.00" in row


def test_anytime_refuses_records_it_did_not_write(capsys, tmp_path):
    from cli_run import run

    bad = tmp_path / "records.json"
    bad.write_text('{"not": "a list"}')
    status, _, err = run(capsys, "bench", "anytime", "--compare", bad)
    assert status == 2 and "not a list of bench anytime records" in err
    status, _, err = run(capsys, "bench", "anytime", "--compare", tmp_path / "missing.json")
    assert status == 2 and "not found" in err
