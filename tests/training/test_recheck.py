"""``fetchcarry benchmark --check RESULTS.json``: recorded episodes run again, compared field by field, timings aside.

A reproduction's own run folders are checked in ``test_reproduce.py`` (on its smoke table).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.cli_run import run
from training.cli import main
from training.evaluation.recheck import MISSING, differences, is_timing, wall_clock_bound
from training.evaluation.results import read_results, write_results


@pytest.fixture(scope="module")
def greedy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``fetchcarry benchmark --policies greedy --split iid --episodes 2``: expert, random-phases and greedy."""
    out = tmp_path_factory.mktemp("check") / "iid"
    argv = ["benchmark", "--policies", "greedy", "--split", "iid", "--episodes", "2", "--no-progress"]
    assert main([*argv, "--out", str(out)]) == 0
    return out / "results.json"


def test_an_untouched_file_comes_out_identical(greedy: Path, capsys) -> None:
    status, out, _ = run(capsys, "benchmark", "--check", greedy, "--policies", "greedy", "expert", "random-phases",
                         "--no-progress")  # fmt: skip
    assert status == 0
    assert "6 of 6 records identical (timings aside: decision_ms, mask_ms, step_ms)" in out
    status, out, _ = run(capsys, "benchmark", "--check", greedy, "--policies", "greedy", "--workers", "2",
                         "--no-progress")  # fmt: skip
    assert status == 0 and "2 of 2 records identical" in out and "4 records of other policies" in out


def test_a_tampered_record_is_reported_and_a_changed_timing_is_not(greedy: Path, tmp_path: Path, capsys) -> None:
    records = read_results(greedy)
    (k,) = [k for k, r in enumerate(records) if r["policy"] == "greedy" and r["seed"] == 1008500001]
    timed = [{**r, "step_ms": r["step_ms"] * 3, "decision_ms": 0.0} if r["policy"] == "greedy" else r for r in records]
    write_results(tmp_path / "timed.json", timed)
    status, out, _ = run(capsys, "benchmark", "--check", tmp_path / "timed.json", "--policies", "greedy",
                         "--no-progress")  # fmt: skip
    assert status == 0 and "2 of 2 records identical" in out
    tampered = [dict(r) for r in records]
    tampered[k]["cost"] += 0.25  # a task cost a quarter higher, its return a quarter lower: still a valid record
    tampered[k]["return"] -= 0.25
    tampered[k]["phases"] += 1
    write_results(tmp_path / "tampered.json", tampered)
    status, out, _ = run(capsys, "benchmark", "--check", tmp_path / "tampered.json", "--policies", "greedy",
                         "--no-progress")  # fmt: skip
    assert status == 1
    assert "1 of 2 records identical" in out
    cost = records[k]["cost"]
    line = (
        f"greedy iid-v2:test seed 1008500001: cost {cost + 0.25:.6g} recorded, {cost:.6g} re-run; "
        f"return {-cost - 0.25:.6g} recorded, {-cost:.6g} re-run; phases"
    )
    assert line in out


def test_only_the_splits_asked_for_are_run_again(greedy: Path, capsys) -> None:
    status, out, _ = run(capsys, "benchmark", "--check", greedy, "--policies", "greedy", "--split", "iid-v2:test",
                         "--no-progress")  # fmt: skip
    assert status == 0 and "2 of 2" in out
    status, _, err = run(capsys, "benchmark", "--check", greedy, "--policies", "greedy", "--split", "layouts")
    assert status == 2 and "holds no record of greedy" in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--policies", "random"], "holds no record of random"),
        (["--policies", "greedy", "--out", "x"], "leave out --out"),
        (["--policies", "greedy", "--episodes", "3"], "leave out --episodes"),
        (["--policies", "no-such-policy"], "no-such-policy"),
    ],
)
def test_bad_input_exits_2(greedy: Path, capsys, argv: list[str], message: str) -> None:
    status, _, err = run(capsys, "benchmark", "--check", greedy, *argv)
    assert status == 2 and message in err


def test_records_of_a_scenario_folder_and_a_benchmark_without_out_are_refused(tmp_path: Path, capsys) -> None:
    record = {"policy": "greedy", "scenario": "a", "split": "scenarios:mine", "source": "a.json", "seed": 0,
              "digest": "0" * 64, "success": True, "delivered": 1, "objects": 1, "cost": 1.0, "expert_cost": 1.0,
              "return": 1.0, "phases": 3, "pushes": 0, "invalid_actions": 0, "contacts": 0, "decision_ms": 1.0,
              "mask_ms": 1.0}  # fmt: skip
    write_results(tmp_path / "results.json", [record])
    status, _, err = run(capsys, "benchmark", "--check", tmp_path / "results.json", "--policies", "greedy")
    assert status == 2 and "only a split's episodes can be checked" in err
    status, _, err = run(capsys, "benchmark", "--policies", "greedy", "--split", "iid")
    assert status == 2 and "give --out" in err
    status, _, err = run(capsys, "benchmark", "--check", tmp_path / "none.json", "--policies", "greedy")
    assert status == 2 and "none.json" in err


def test_differences_leave_out_timings_and_fields_beyond_the_benchmarks() -> None:
    recorded = {"policy": "p", "cost": 1.5, "decision_ms": 3.0, "baseline": "p", "training_seed": 0}
    rerun = {"policy": "p", "cost": 1.5, "decision_ms": 9.0, "step_ms": 4.0, "index": 3}
    assert differences(recorded, rerun) == {}
    assert differences(recorded, {**rerun, "cost": 1.5000001}) == {"cost": (1.5, 1.5000001)}
    assert differences(recorded, {**rerun, "pushes": 0}) == {"pushes": (MISSING, 0)}
    assert differences({**recorded, "cost": 2}, {**rerun, "cost": 2.0}) == {}  # as JSON holds them
    assert is_timing("mask_ms") and is_timing("planning_s") and not is_timing("pushes")
    assert json.loads(json.dumps(differences(recorded, {**rerun, "success": False})))  # printable


def test_the_expert_is_wall_clock_bound_where_its_reference_was_slow_or_unproven() -> None:
    expert = {"policy": "expert", "split": "apartment-v1:test", "seed": 1006500001, "decision_ms": 40.0, "phases": 5}
    # (apartment-v1 seed 1006500001: no plan proven in 60 s)
    assert wall_clock_bound(expert)
    assert wall_clock_bound({**expert, "seed": 1006500000})  # proven, in 55 s
    assert not wall_clock_bound({**expert, "split": "iid-v1:test", "seed": 1000500000})  # proven in 0.06 s
    assert not wall_clock_bound({**expert, "split": "iid-v2:test", "seed": 1008500000})  # proven in 0.04 s
    assert not wall_clock_bound({**expert, "policy": "greedy"})
    # a fast reference, but this episode's decisions took the 10 s safety stop in all: a loaded machine's
    assert wall_clock_bound({**expert, "split": "iid-v2:test", "seed": 1008500000, "decision_ms": 2000.0})
    assert wall_clock_bound({**expert, "split": "scenarios:mine", "seed": 0})  # no fixed reference
