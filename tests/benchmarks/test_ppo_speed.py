"""The speed benchmarks of the learnable interface: ``python -m benchmarks ppo`` and ``phases --split``."""

from __future__ import annotations

import json

import pytest

from benchmarks.cli import main
from benchmarks.speed.phases import time_split


def test_bench_ppo_prints_steps_per_second_per_env_count(capsys: pytest.CaptureFixture) -> None:
    assert main(["ppo", "--steps", "16", "--n-steps", "16", "--envs", "1,2", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    rows = report["results"]
    assert [row["envs"] for row in rows] == [1, 2]
    assert all(row["steps"] >= 16 and row["steps_per_s"] > 0 for row in rows)
    assert all(0 < row["rollout_seconds"] <= row["seconds"] for row in rows)


@pytest.mark.parametrize("envs", ["0", "1,x", "", "65"])
def test_bench_ppo_refuses_impossible_env_counts(envs: str, capsys: pytest.CaptureFixture) -> None:
    assert main(["ppo", "--envs", envs]) == 2
    assert "--envs" in capsys.readouterr().err


def test_the_phases_split_accounts_for_both_walks(capsys: pytest.CaptureFixture) -> None:
    split = time_split("basic", 12)
    assert set(split["phases"]) == {"resets", "reset", "mask", "step"}
    assert set(split["plain"]) == {"resets", "reset", "policy", "step"}
    assert split["phases"]["resets"] >= 1 and all(v > 0 for v in split["phases"].values())
    assert split["sample_ms"] > 0
    assert main(["phases", "--speed-only", "--split", "--steps", "5", "--families", "basic"]) == 0
    assert "where the time goes" in capsys.readouterr().out
