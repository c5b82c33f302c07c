"""The speed benchmarks (``benchmarks.speed``, ``python -m benchmarks ...``): they run and print the right shape.

No timings are checked here: the goals are figures the benchmarks print, never test assertions.
"""

from __future__ import annotations

import io
import json
from argparse import Namespace

import pytest
from cli_run import bench

from benchmarks.cli import main as benchmarks_main
from benchmarks.speed import anytime, generate, planner, push
from benchmarks.speed import env as env_speed
from benchmarks.speed.commands import run_bench_push, run_planner
from fetchcarry_env.errors import InputError
from training.data.sources import EpisodeSource

TINY_ENV = ["--episodes", "2", "--resets", "4", "--random-steps", "20", "--obs-episodes", "1", "--no-progress"]


# ---------------------------------------------------------------------- bench env
def test_env_benchmark_prints_every_figure_as_json_on_a_clean_stdout(capfd):
    assert benchmarks_main(["env", *TINY_ENV, "--json"]) == 0
    report = json.loads(capfd.readouterr().out)  # nothing but JSON on stdout (PyBullet prints nothing)
    figures = {f["name"]: f for f in report["figures"]}
    assert set(figures) == {
        "reset, same layout",
        "reset, new layout (bodies rebuilt)",
        "reset, a new 'push' scenario (draw, check, build)",
        "move step",
        "pick step",
        "place step",
        "push step (0.15 m stroke), time / its physics steps' time",
        "random masked policy",
        "plan step, obs_mode state",
        "obs_mode topdown (64, world): added to a step",
        "obs_mode rgbd (128, tiny): added to a step",
        "one observation, obs_mode state",
        "one observation, obs_mode topdown",
        "one observation, obs_mode rgbd",
        "peak memory of the process (resident)",
    }
    assert all(f["value"] > 0 for f in figures.values())
    push_step = figures["push step (0.15 m stroke), time / its physics steps' time"]
    assert push_step["value"] >= 1.0  # a step cannot be faster than the physics it simulates
    assert "physics steps" in push_step["floor"] and push_step["goal"] == "1.5 or less"
    assert "in 12 physics steps" in figures["place step"]["floor"]
    for name, goal in (
        ("reset, same layout", "under 2 ms"),
        ("move step", "2,000 or more"),
        ("place step", "500 or more"),
    ):
        assert figures[name]["goal"] == goal and isinstance(figures[name]["met"], bool)
    assert report["random_policy"]["episodes"] >= 1
    assert figures["one observation, obs_mode topdown"]["value"] == pytest.approx(0.95 + 7 * 64 * 64 / 1024, abs=0.01)
    assert figures["obs_mode topdown (64, world): added to a step"]["goal"] == "0.3 ms or less"


def test_env_table_names_goals_and_floors(capsys):
    assert benchmarks_main(["env", *TINY_ENV]) == 0
    out = capsys.readouterr().out
    assert out.startswith("env benchmark: FetchCarryPush-v0 on PyBullet")
    for text in ("reset, same layout", "push step", "random masked policy", "PyBullet floor", "physics steps"):
        assert text in out


def test_env_strict_exits_1_only_when_a_goal_is_missed(monkeypatch, capsys):
    report = {
        "env": "FetchCarryPush-v0",
        "pybullet": "3.2.7",
        "scenario": "s",
        "episodes": 1,
        "seed": 0,
        "wall_s": 1.0,
        "random_steps": 1,
        "random_policy": {"episodes": 1, "invalid_actions": 0, "collisions": 0, "pushes": 0},
        "figures": [
            {"name": "move step", "value": 10.0, "unit": "per s", "goal": "2,000 or more", "met": False, "floor": None}
        ],
    }
    monkeypatch.setattr(env_speed, "measure", lambda *args, **kwargs: report)
    assert benchmarks_main(["env"]) == 0
    assert benchmarks_main(["env", "--strict"]) == 1
    assert "NO" in capsys.readouterr().out


def test_env_bad_options_exit_2_with_a_message(capsys):
    with pytest.raises(SystemExit) as exit_info:
        benchmarks_main(["env", "--episodes", "0"])
    assert exit_info.value.code == 2
    assert "expected a positive number, got 0" in capsys.readouterr().err


# ---------------------------------------------------------------------- bench planner
def planner_args(**changes) -> Namespace:
    base = {"seed": 1, "scale": 0.05, "only": ["V-B", "L"], "time_limit": 30.0, "baseline": False, "json": False}
    return Namespace(**{**base, **changes})


def test_planner_tiny_run_prints_paper_and_goal_tables():
    out = io.StringIO()
    assert run_planner(planner_args(), out) == 0
    text = out.getvalue()
    for expected in ("V-B area III", "IV-F L corridor", "0.22 (0.20)", "median 20, p95 50", "where the time goes"):
        assert expected in text
    assert "not optimal" not in text
    breakdown = text.split("where the time goes")[1].splitlines()[2:]
    assert [line.split()[0] for line in breakdown] == ["V-B", "L"]
    assert all(len(line.split()) == 7 for line in breakdown)  # group, five shares, extra N tried


def test_planner_json_lists_every_run():
    out = io.StringIO()
    assert run_planner(planner_args(json=True), out) == 0
    data = json.loads(out.getvalue())
    assert len(data["runs"]) == 6  # five V-B areas and the corridor, one scenario each
    assert all(r["status"] == "optimal" and r["valid"] for r in data["runs"])
    assert data["cases"]["V-B area I"]["paper"] == "0.05 (0.02)"
    assert {r["scenario"] for r in data["runs"]} == {"vb-I", "vb-II", "vb-III", "vb-IV", "vb-V", "corridor-L"}


def test_planner_unknown_group_is_a_usage_error():
    with pytest.raises(InputError, match="nope"):
        run_planner(planner_args(only=["nope"]), io.StringIO())


def test_planner_command_parses_its_options(capsys):
    assert benchmarks_main(["planner", "--scale", "0.05", "--only", "L", "--seed", "3"]) == 0
    assert "IV-F L corridor" in capsys.readouterr().out


def test_help_shows_no_docstring_markup(capsys):
    for what in ("planner", "env", "generate", "anytime", "push"):
        with pytest.raises(SystemExit):
            benchmarks_main([what, "--help"])
        text = capsys.readouterr().out
        assert ":mod:" not in text and ":func:" not in text and "``" not in text, what


def test_every_case_draws_from_a_family_and_the_scale_cases_are_there():
    from fetchcarry_env.families import PAPER_FAMILY_NAMES

    rows = planner.cases()
    assert {c.family for c in rows} == set(PAPER_FAMILY_NAMES)
    assert {"4 obj", "5 obj", "6 obj", "cov 2", "cov 3"} <= {c.group for c in rows}
    assert planner.groups(rows)[:3] == ["V-B", "V-C", "L"]
    assert [c.repeats for c in planner.cases(0.01)] == [1] * len(rows)


def test_planner_goal_and_shares():
    case = planner.Case("x", "g", "paper-corridor", 1, "-", goal_median_s=0.02, goal_p95_s=0.05)
    assert planner.goal_met(case, {"median_s": 0.01, "p95_s": 0.06}) is False
    assert planner.goal_met(case, {"median_s": 0.01, "p95_s": 0.04}) is True
    assert planner.goal_met(planner.Case("x", "g", "paper-corridor", 1, "-"), {"median_s": 9.0}) is None
    runs = [planner.Run("x", "g", "s", "optimal", 4, 1.0, 0.1, 0.2, 0.3, 0.3, [4, 5])]
    shares = planner.time_shares(runs)
    assert shares["other"] == pytest.approx(0.1) and shares["extra_n_tried"] == 1.0


# ---------------------------------------------------------------------- bench anytime
def _anytime_record(index: int, limit: float, objective: float, phases: int = 8, **changes) -> dict:
    record = {"group": "4 obj", "index": index, "limit": limit, "reference": limit == 30.0, "status": "optimal",
              "phases": phases, "objective": objective, "gap": 0.0, "seconds": 0.05, "valid": True}  # fmt: skip
    return {**record, **changes}


def test_anytime_summary_compares_each_plan_with_its_reference():
    reference = [_anytime_record(0, 30.0, 10.0), _anytime_record(1, 30.0, 20.0)]
    short = [
        _anytime_record(0, 0.1, 10.4, status="time_limit", gap=None),  # 4 % above: within 5 %
        _anytime_record(1, 0.1, 22.0, status="time_limit", gap=0.08),  # 10 % above
    ]
    lines = anytime.summary(short + reference, reference)
    row = next(line for line in lines if line.startswith("4 obj") and "0.10" in line)
    assert row.split()[3:7] == ["2/2", "0", "2", "1"]  # valid, optimal, reference's phases, within 5 %
    assert "4.00, 10.00 / 8.00" in row


def test_anytime_groups_draw_from_paper_families():
    assert set(anytime.FAMILIES) == set(anytime.COUNTS)
    assert all(name.startswith("paper-") for name in anytime.FAMILIES.values())


def test_anytime_refuses_records_it_did_not_write(capsys, tmp_path):
    bad = tmp_path / "records.json"
    bad.write_text('{"not": "a list"}')
    status, _, err = bench(capsys, "anytime", "--compare", bad)
    assert status == 2 and "not a list of bench anytime records" in err
    status, _, err = bench(capsys, "anytime", "--compare", tmp_path / "missing.json")
    assert status == 2 and "not found" in err


# ---------------------------------------------------------------------- bench push
def _push_record(name: str, group: str, travel: float, phases: int = 6, holding: int = 1) -> dict:
    return {"group": group, "name": name, "status": "optimal", "phases": phases, "travel": travel,
            "objective": travel - 10.0, "holding_pushes": holding, "seconds": 0.02}  # fmt: skip


def test_push_scenarios_come_from_the_push_and_paper_push_families():
    groups = [group for group, _, _ in push.scenarios()]
    assert groups.count("push family") == push.FAMILY_SEEDS
    assert {g for g in groups if g.startswith("pattern")} == {f"pattern {p}" for p in "ABCDE"}
    assert len(groups) == push.FAMILY_SEEDS + 5 * push.PATTERN_SEEDS


def test_push_summary_and_compare_shapes():
    after = [_push_record("push-0", "push family", 8.0), _push_record("A-0", "pattern A", 7.0, phases=6)]
    before = [_push_record("push-0", "push family", 14.0, 7, 0), _push_record("A-0", "pattern A", 12.0, 6, 0)]
    table = push.summary(after)
    assert table[0].split()[:2] == ["group", "plans"] and len(table) == 3
    assert table[1].split() == ["push", "family", "1", "6.00", "8.00", "1", "0.020"]
    lines = push.compare(after, before)
    assert [line.split()[0] for line in lines[1:]] == ["all", "push", "pattern"]
    assert lines[1].split()[1:4] == ["2", "13.00", "7.50"]


def test_push_command_writes_and_compares_records(monkeypatch, tmp_path):
    records = [_push_record("push-0", "push family", 8.0)]
    monkeypatch.setattr(push, "measure", lambda: records)
    before = tmp_path / "before.json"
    before.write_text(json.dumps([_push_record("push-0", "push family", 14.0, 7, 0)]))
    out = io.StringIO()
    after = tmp_path / "after.json"
    assert run_bench_push(Namespace(out=str(after), compare=str(before)), out) == 0
    assert json.loads(after.read_text()) == records
    text = out.getvalue()
    assert "holding-push plans" in text and "travel before" in text


def test_push_refuses_records_it_did_not_write(capsys, tmp_path):
    bad = tmp_path / "records.json"
    bad.write_text("[1, 2]")
    status, _, err = bench(capsys, "push", "--compare", bad)
    assert status == 2 and "not a list of bench push records" in err


# ---------------------------------------------------------------------- bench generate
def test_generation_gives_one_row_per_worker_count():
    source = EpisodeSource(family="basic", seed=0, policy="random", time_limit=1.0)
    rows = generate.generation(source, 1, [1])
    assert [row["workers"] for row in rows] == [1]
    assert rows[0]["episodes"] == 1 and rows[0]["speed_up"] == 1.0
    assert {"episodes_per_s", "planning_s_per_episode", "simulation_s_per_episode", "planning_share"} <= rows[0].keys()
