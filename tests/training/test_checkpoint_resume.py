"""``fetchcarry train bc --resume`` on a hostile ``checkpoint.pt``: exit 2 naming the file and the field.

Red-team item 7 of "The first hour": ``{}`` was exit 3 (``KeyError: 'network'``), a bad
``order`` exit 3 (``TypeError``), tensors of the wrong shapes exit 3 (``RuntimeError``).
Each test interrupts a small BC run after its first epoch (so its folder holds a
checkpoint), edits the checkpoint, and resumes the run through the command line.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import torch
from cli_run import run

from training.cli import main
from training.learners import runs

DATASET_ID = "fetchcarry/resume-v0"
TRAIN = ("train", "bc", "--dataset", DATASET_ID, "--epochs", "2", "--hidden", "16", "--no-progress")


@pytest.fixture(scope="module")
def interrupted(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A Minari folder with a small phases dataset, and a BC run on it interrupted after its first epoch."""
    root = tmp_path_factory.mktemp("minari")
    folder = tmp_path_factory.mktemp("runs") / "run"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(root))
        assert main(["generate", "--family", "basic", "--episodes", "2", "--interface", "phases", "--dataset-id",
                     DATASET_ID, "--no-progress"]) == 0  # fmt: skip

        def interrupt(out: Path, rows: list) -> None:
            raise KeyboardInterrupt  # after the first epoch's checkpoint was saved

        patch.setattr(runs, "write_metrics", interrupt)
        assert main([*TRAIN, "--out", str(folder)]) == 130
    assert runs.load_checkpoint(folder)["epoch"] == 1
    return root, folder


@pytest.fixture
def folder(interrupted: tuple[Path, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """This test's copy of the interrupted run folder (the dataset where the run expects it)."""
    root, original = interrupted
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(root))
    copy = tmp_path / "run"
    shutil.copytree(original, copy)
    return copy


def edit_checkpoint(folder: Path, change: Callable[[dict[str, Any]], Any]) -> None:
    """Save the checkpoint again after ``change`` edited its state in place (what ``change`` returns is ignored)."""
    file = folder / runs.CHECKPOINT_FILE
    state = torch.load(file, weights_only=True)
    change(state)
    torch.save(state, file)


def replace_checkpoint(folder: Path, content: Callable[[dict[str, Any]], Any]) -> None:
    """Save ``content(state)`` in the checkpoint's place."""
    file = folder / runs.CHECKPOINT_FILE
    torch.save(content(torch.load(file, weights_only=True)), file)


def resume(capsys: pytest.CaptureFixture, folder: Path) -> tuple[int, str, str]:
    return run(capsys, *TRAIN, "--out", folder, "--resume")


def assert_refused(capsys: pytest.CaptureFixture, folder: Path, *words: str) -> None:
    status, _, err = resume(capsys, folder)
    assert status == 2, err
    assert str(folder / runs.CHECKPOINT_FILE) in err and all(word in err for word in words), err
    assert "internal error" not in err
    assert not (folder / runs.WEIGHTS_FILE).exists()


# ---------------------------------------------------------------------------- the red team's three
def test_an_empty_checkpoint_is_refused_naming_its_missing_fields(capsys, folder: Path) -> None:
    replace_checkpoint(folder, lambda state: {})
    assert_refused(capsys, folder, "missing", "network")


def test_a_bad_order_is_refused(capsys, folder: Path) -> None:
    edit_checkpoint(folder, lambda state: state.update(order="x"))
    assert_refused(capsys, folder, "order")


def test_an_order_of_the_right_size_that_no_generator_takes_is_refused(capsys, folder: Path) -> None:
    edit_checkpoint(folder, lambda state: state.update(order=torch.zeros_like(state["order"])))
    assert_refused(capsys, folder, "order")


def test_network_tensors_of_the_wrong_shapes_are_refused(capsys, folder: Path) -> None:
    names: list[str] = []

    def reshape(state: dict[str, Any]) -> None:
        names.extend(state["network"])
        state["network"] = {key: torch.zeros(3, 3) for key in state["network"]}

    edit_checkpoint(folder, reshape)
    assert_refused(capsys, folder, f"network.{names[0]} must be a float32 tensor of shape", "(3, 3)")


# ---------------------------------------------------------------------------- every other field
def test_a_network_missing_a_tensor_is_refused(capsys, folder: Path) -> None:
    edit_checkpoint(folder, lambda state: state["network"].pop("layers.0.bias"))
    assert_refused(capsys, folder, "network", "layers.0.bias")


def test_a_network_of_another_dtype_is_refused(capsys, folder: Path) -> None:
    edit_checkpoint(folder, lambda state: state["network"].update({k: v.double() for k, v in state["network"].items()}))
    assert_refused(capsys, folder, "network.", "float64")


def test_optimiser_moments_of_the_wrong_shape_are_refused(capsys, folder: Path) -> None:
    edit_checkpoint(folder, lambda state: state["optimiser"]["state"][0].update(exp_avg=torch.zeros(2)))
    assert_refused(capsys, folder, "optimiser.state[0].exp_avg")


def test_an_optimiser_learning_rate_that_is_not_the_runs_is_refused(capsys, folder: Path) -> None:
    edit_checkpoint(folder, lambda state: state["optimiser"]["param_groups"][0].update(lr="fast"))
    assert_refused(capsys, folder, "optimiser.param_groups[0].lr")


def test_an_optimiser_that_is_not_a_state_dict_is_refused(capsys, folder: Path) -> None:
    edit_checkpoint(folder, lambda state: state.update(optimiser=[1, 2]))
    assert_refused(capsys, folder, "optimiser")


def test_a_sparse_tensor_is_refused(capsys, folder: Path) -> None:
    edit_checkpoint(folder, lambda state: state["network"].update({"layers.0.bias": state["network"]["layers.0.bias"]
                                                                   .to_sparse()}))  # fmt: skip
    assert_refused(capsys, folder, "network.layers.0.bias", "is not dense")


def test_metric_rows_without_their_columns_are_refused(capsys, folder: Path) -> None:
    edit_checkpoint(folder, lambda state: state["metrics"][0].pop("seconds"))
    assert_refused(capsys, folder, "metrics[0] lacks seconds")


def test_metric_rows_that_are_not_the_epochs_done_are_refused(capsys, folder: Path) -> None:
    edit_checkpoint(folder, lambda state: state.update(metrics=[]))
    assert_refused(capsys, folder, "metrics")


def test_unknown_extra_content_is_refused(capsys, folder: Path) -> None:
    edit_checkpoint(folder, lambda state: state.update(payload=torch.zeros(10)))
    assert_refused(capsys, folder, "unknown", "payload")


def test_a_checkpoint_that_is_not_a_dict_is_refused(capsys, folder: Path) -> None:
    replace_checkpoint(folder, lambda state: [state])
    assert_refused(capsys, folder, "does not hold a training checkpoint")


class _Planted:
    """A pickle that would write a marker file if it were loaded without ``weights_only``."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (self.marker,))


def test_a_checkpoint_pickling_code_is_not_run(capsys, folder: Path, tmp_path: Path) -> None:
    marker = tmp_path / "MARKER"
    torch.save({"network": _Planted(marker)}, folder / runs.CHECKPOINT_FILE)
    assert_refused(capsys, folder, "is not a file of tensors")
    assert not marker.exists()


# ---------------------------------------------------------------------------- the untouched checkpoint
def test_a_valid_checkpoint_still_resumes_to_the_end(capsys, folder: Path) -> None:
    status, _, err = resume(capsys, folder)
    assert status == 0, err
    assert runs.read_config(folder)["complete"] and (folder / runs.WEIGHTS_FILE).exists()
    assert [row["epoch"] for row in runs.read_metrics(folder)] == [1, 2]
