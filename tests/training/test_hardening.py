"""Hardening (issue 8, sections 1-3): no code from a data file, exit statuses, datasets never corrupted.

Every test here reproduces one attack or fault of the issue through the command line
(in-process through ``training.cli.main``, or a subprocess where signals are involved).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from training.cli import main
from training.datasets import dataset_path

DATASET_ID = "fetchcarry/hard-v0"


def run(capsys: pytest.CaptureFixture, *argv: str) -> tuple[int, str, str]:
    """``fetchcarry argv...`` in-process: (exit status, stdout, stderr); never a traceback."""
    try:
        status = main([str(a) for a in argv])
    except SystemExit as exit_:
        status = exit_.code
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return status, out, err


def generate_random(capsys: pytest.CaptureFixture, dataset_id: str = DATASET_ID, episodes: int = 2, *extra: str):
    """A small dataset of the random policy (fast: no planner)."""
    return run(
        capsys, "generate", "--family", "basic", "--policy", "random", "--episodes", str(episodes),
        "--dataset-id", dataset_id, "--no-progress", *extra,
    )  # fmt: skip


@pytest.fixture
def dataset(capsys: pytest.CaptureFixture) -> str:
    status, _, err = generate_random(capsys)
    assert status == 0, err
    return DATASET_ID


def edit_env_spec(dataset_id: str, **changes) -> None:
    metadata_file = dataset_path(dataset_id) / "data" / "metadata.json"
    metadata = json.loads(metadata_file.read_text())
    spec = json.loads(metadata["env_spec"])
    spec.update(changes)
    metadata["env_spec"] = json.dumps(spec)
    metadata_file.write_text(json.dumps(metadata))


# ---------------------------------------------------------------------------- 1. a dataset runs no code
@pytest.mark.parametrize(
    "changes",
    [
        {"entry_point": "os:system"},  # the attack: the "env" is a shell command
        {"id": "Evil-v0", "entry_point": "os:system"},
        {"id": "CartPole-v1", "entry_point": "gymnasium.envs.classic_control.cartpole:CartPoleEnv", "kwargs": {}},
        {"kwargs": {"family": "basic", "capacity": "x"}},  # a keyword the env is not given from a dataset
        {"kwargs": {"scenario": "/etc/passwd"}},  # a path: the dataset would make the env read another file
        {"additional_wrappers": [{"name": "W", "entry_point": "os:system", "kwargs": {}}]},
    ],
    ids=["entry-point", "unknown-id", "foreign-env", "extra-kwarg", "scenario-path", "wrapper"],
)
def test_replay_refuses_a_dataset_that_names_an_unknown_env(capsys, tmp_path: Path, dataset: str, changes) -> None:
    marker = tmp_path / "ran"
    if changes.get("entry_point") == "os:system":
        changes = {**changes, "kwargs": {"command": f"touch {marker}"}}
    edit_env_spec(dataset, **changes)
    status, out, err = run(capsys, "dataset", "replay", dataset, "--episode", "0")
    assert status == 2 and out == ""
    assert "names an unknown env" in err
    assert not marker.exists()


def test_replay_of_an_untouched_dataset_still_works(capsys, dataset: str) -> None:
    status, out, _ = run(capsys, "dataset", "replay", dataset, "--episode", "1")
    assert status == 0 and ": reproduced" in out
