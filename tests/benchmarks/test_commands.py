"""``python -m benchmarks generate|phases|projection|learning-checks``: they run, print their figures, refuse bad input.

Run in-process (:func:`cli_run.bench`). Exit statuses: 0 measured, 2 bad input with a short
message on stderr and never a traceback.
"""

from __future__ import annotations

import json
from pathlib import Path

from cli_run import bench


def test_generate_prints_the_split_and_the_speed_up(capsys) -> None:
    argv = ["generate", "--families", "basic,push", "--episodes", "2", "--workers", "1", "--json"]
    status, out, _ = bench(capsys, *argv)
    runs = json.loads(out)["runs"]
    assert status == 0 and [row["family"] for row in runs] == ["basic", "push"]
    for row in runs:
        assert row["speed_up"] == 1.0 and row["successes"] == 2
        assert 0 < row["planning_s_per_episode"] <= row["policy_s_per_episode"]
        assert row["simulation_s_per_episode"] > 0 and 0 < row["planning_share"] < 1
    status, out, _ = bench(capsys, "generate", "--families", "basic", "--episodes", "1", "--workers", "1")
    assert status == 0 and "ep/s/worker" in out and "speed-up" in out


def test_phases_prints_the_expert_in_the_interface_and_its_speed(capsys) -> None:
    status, out, _ = bench(capsys, "phases", "--families", "basic,push", "--episodes", "2", "--steps", "20")
    assert status == 0
    expressed, speed = out.split("\nspeed ")
    rows = [line.split() for line in expressed.splitlines()[2:]]
    assert [row[0] for row in rows] == ["basic", "push"] and all(row[1] == "100%" for row in rows)
    assert "pick 2/2" in expressed  # one pick per episode, each an allowed candidate
    assert [line.split()[0] for line in speed.splitlines()[2:]] == ["basic", "push"]
    assert "0, stopped at a contact 0" in speed  # the mask never allows a step the env refuses
    status, _, err = bench(capsys, "phases", "--families", "nope")
    assert status == 2 and "unknown family" in err


def test_projection_compares_the_recorded_expert_with_its_own_episodes(capsys) -> None:
    status, out, _ = bench(capsys, "projection", "--family", "basic", "--episodes", "3")
    figures = json.loads(out)
    assert status == 0 and figures["episodes"] == 3 and figures["success"] == figures["expert_success"] == 1.0
    assert 0 <= figures["episodes_with_projection"] <= 1 and figures["projected_per_episode"] >= 0
    status, _, err = bench(capsys, "projection", "--family", "nope")
    assert status == 2 and "unknown family" in err


def test_learning_checks_bc_trains_and_compares_with_the_baselines(capsys, tmp_path: Path) -> None:
    argv = ["learning-checks", "bc", "--episodes", "3", "--eval-episodes", "2", "--encoders", "mlp"]
    status, out, _ = bench(capsys, *argv, "--epochs", "2", "--out", str(tmp_path))
    assert status == 0 and "the expert solved 2/2 held-out seeds" in out
    assert [line.split()[0] for line in out.splitlines()[-3:]] == ["random", "greedy", "bc-mlp"]
    assert (tmp_path / "bc-mlp" / "model.pt").is_file()
    status, _, err = bench(capsys, "learning-checks", "ppo", "--family", "nope")
    assert status == 2 and "unknown family" in err
