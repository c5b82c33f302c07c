"""``fetchcarry bench env``: figures, goals, JSON and exit statuses."""

from __future__ import annotations

import json

import pytest

from fetchcarry_env import bench
from training.cli import main as fetchcarry

TINY = ["--episodes", "2", "--resets", "4", "--random-steps", "20", "--no-progress"]


def test_the_benchmark_prints_every_figure_as_json_on_a_clean_stdout(capfd):
    assert fetchcarry(["bench", "env", *TINY, "--json"]) == 0
    out = capfd.readouterr().out
    report = json.loads(out)  # nothing but JSON on stdout (PyBullet prints nothing)
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
        "peak memory of the process (resident)",
    }
    assert all(f["value"] > 0 for f in figures.values())
    push = figures["push step (0.15 m stroke), time / its physics steps' time"]
    assert push["value"] >= 1.0  # a step cannot be faster than the physics it simulates
    assert "physics steps" in push["floor"] and push["goal"] == "1.5 or less"
    assert "in 12 physics steps" in figures["place step"]["floor"]
    for name, goal in (
        ("reset, same layout", "under 2 ms"),
        ("move step", "2,000 or more"),
        ("place step", "500 or more"),
    ):
        assert figures[name]["goal"] == goal and isinstance(figures[name]["met"], bool)
    assert report["random_policy"]["episodes"] >= 1


def test_the_table_names_goals_and_floors(capsys):
    assert fetchcarry(["bench", "env", *TINY]) == 0
    out = capsys.readouterr().out
    assert out.startswith("env benchmark: FetchCarryPush-v0 on PyBullet")
    for text in ("reset, same layout", "push step", "random masked policy", "PyBullet floor", "physics steps"):
        assert text in out


def test_strict_exits_1_only_when_a_goal_is_missed(monkeypatch, capsys):
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
    monkeypatch.setattr(bench, "run_benchmark", lambda *args, **kwargs: report)
    assert fetchcarry(["bench", "env"]) == 0
    assert fetchcarry(["bench", "env", "--strict"]) == 1
    assert "NO" in capsys.readouterr().out


def test_bad_options_exit_2_with_a_message(capsys):
    with pytest.raises(SystemExit) as exit_info:
        fetchcarry(["bench", "env", "--episodes", "0"])
    assert exit_info.value.code == 2
    assert "expected a positive number, got 0" in capsys.readouterr().err
