"""A new learned baseline is one module plus one registry entry: train, load and benchmark a throwaway one."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest
import throwaway_learner
from cli_run import run

import training
from training.evaluation.results import read_results
from training.learners import registry
from training.learners.runs import RunFolderError


@pytest.fixture
def first_allowed() -> Iterator[registry.Learner]:
    """The throwaway learner, registered for one test."""
    learner = registry.register(throwaway_learner.LEARNER)
    yield learner
    registry.unregister(learner.kind)


def test_a_registered_learner_trains_loads_and_benchmarks(first_allowed, capsys, tmp_path: Path) -> None:
    status, out, err = run(capsys, "train", "first-allowed", "--help")
    assert status == 0 and "--family NAME" in out and "--seed N" in out and "[--resume]" not in out
    run_dir = tmp_path / "first"
    status, out, err = run(capsys, "train", "first-allowed", "--family", "basic", "--seed", "3", "--out", run_dir)
    assert status == 0, err
    assert out == f"first-allowed trained\nrun folder {run_dir}\n"
    assert json.loads((run_dir / "config.json").read_text())["options"] == {"family": "basic", "seed": 3}
    policy = training.load_policy(run_dir)
    assert isinstance(policy, throwaway_learner.FirstAllowedPolicy)
    assert policy.predict(None, action_masks=[False, False, True, True]) == (2, None)
    bench = tmp_path / "bench"
    argv = ["benchmark", "--policies", run_dir, "--split", "iid", "--episodes", 2, "--no-progress", "--out", bench]
    status, out, err = run(capsys, *argv)
    assert status == 0, err
    records = read_results(bench / "results.json")
    ours = [r for r in records if r["policy"] == "first"]  # next to the benchmark's references
    assert [r["source"] for r in ours] == ["basic", "push"] and all(r["phases"] >= 1 for r in ours)


def test_bad_options_of_a_registered_learner_exit_2(first_allowed, capsys, tmp_path: Path) -> None:
    status, _, err = run(capsys, "train", "first-allowed", "--family", "nope", "--out", tmp_path / "x")
    assert status == 2 and "unknown family 'nope'" in err
    status, _, err = run(capsys, "train", "first-allowed", "--family", "basic", "--seed", "x", "--out", tmp_path)
    assert status == 2 and "expected a whole number" in err


def test_a_registered_learner_refuses_evaluation_seeds_by_its_record(first_allowed, capsys, tmp_path: Path) -> None:
    command = ("train", "first-allowed", "--family", "basic", "--seed", 10**9)
    status, _, err = run(capsys, *command, "--out", tmp_path / "a")
    assert status == 2 and "evaluation seeds" in err and not (tmp_path / "a").exists()
    status, _, err = run(capsys, *command, "--allow-evaluation-seeds", "--out", tmp_path / "b")
    assert status == 0, err


def test_a_learner_must_say_how_it_refuses_evaluation_data() -> None:
    with pytest.raises(TypeError, match="refuse"):
        registry.Learner("x", throwaway_learner.FirstAllowedOptions, train="m:f", help="h")  # type: ignore[call-arg]


def test_unregistered_kinds_are_unknown(first_allowed, tmp_path: Path) -> None:
    registry.unregister(first_allowed.kind)
    assert registry.kinds() == ("bc", "dagger", "ppo", "ensemble")
    with pytest.raises(registry.UnknownLearnerError):
        registry.get(first_allowed.kind)
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "config.json").write_text(json.dumps({"kind": first_allowed.kind, "complete": True}))
    with pytest.raises(RunFolderError):  # checked as a run of the BC network, which it is not
        training.load_policy(folder)
    registry.register(first_allowed)  # for the fixture's teardown


def test_a_kind_registers_once() -> None:
    with pytest.raises(ValueError, match="registered already"):
        registry.register(registry.get("bc"))
