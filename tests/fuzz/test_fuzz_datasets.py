"""The fuzz suite for datasets (hardening, round 2): a mutated ``metadata.json`` never crashes a command.

A small dataset of the random policy is generated once; each example writes a mutated
copy of its ``metadata.json`` (:mod:`mutations`: the top level, or inside the env spec
or a space, which the file holds as JSON text; sometimes the bytes mangled too) and
runs ``fetchcarry dataset info`` and ``dataset replay`` in-process. Each exits 0, 1
(a replay that does not reproduce) or 2 with a message naming the dataset's file,
never 3, never a traceback, and nothing a mutated file names is run.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_run import run
from hypothesis import given
from hypothesis import strategies as st
from mutations import file_bytes, mutated, to_json_text
from test_fuzz_inputs import fuzz

DATASET_ID = "fetchcarry/fuzz-v0"
TEXT_FIELDS = ("env_spec", "observation_space", "action_space")  # JSON documents held as strings in the file


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    """The generated dataset's ``metadata.json`` path and its content (under a private MINARI_DATASETS_PATH)."""
    root = tmp_path_factory.mktemp("minari")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(root))
        from training.cli import main

        status = main(["generate", "--family", "basic", "--policy", "random", "--episodes", "2", "--dataset-id",
                       DATASET_ID, "--no-progress"])  # fmt: skip
        assert status == 0
        file = root / DATASET_ID / "data" / "metadata.json"
        yield file, json.loads(file.read_text())


@st.composite
def mutated_metadata(draw: st.DrawFn, metadata: dict) -> bytes:
    """The bytes of a mutated ``metadata.json``: its top level or one of its JSON-text fields mutated."""
    part = draw(st.sampled_from(["metadata", "metadata", *TEXT_FIELDS]))
    document = dict(metadata)
    if part == "metadata":
        document = draw(mutated(document))
    else:
        inner = draw(mutated(json.loads(document[part]), max_mutations=2))
        document[part] = to_json_text(inner)
    return draw(file_bytes(to_json_text(document)))


def check(capsys, metadata_file: Path, *argv: str) -> None:
    status, _, err = run(capsys, *argv)
    assert status in (0, 1, 2), (status, err)
    assert "\x1b" not in err
    err.encode("utf-8")
    if status == 2:
        assert str(metadata_file.parent) in err, err


@fuzz(120)
@given(data=st.data())
def test_dataset_info_of_a_mutated_metadata_file_exits_0_or_2_naming_it(capsys, dataset, data):
    file, metadata = dataset
    file.write_bytes(data.draw(mutated_metadata(metadata)))
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(file.parents[3]))
        check(capsys, file, "dataset", "info", DATASET_ID)


@fuzz(40)
@given(data=st.data())
def test_dataset_replay_of_a_mutated_metadata_file_exits_0_1_or_2_naming_it(capsys, dataset, data):
    file, metadata = dataset
    file.write_bytes(data.draw(mutated_metadata(metadata)))
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(file.parents[3]))
        check(capsys, file, "dataset", "replay", DATASET_ID, "--episode", "1")


def test_the_untouched_dataset_is_read(capsys, dataset):
    file, metadata = dataset
    file.write_text(json.dumps(metadata))
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(file.parents[3]))
        status, out, err = run(capsys, "dataset", "replay", DATASET_ID, "--episode", "1")
    assert status == 0 and ": reproduced" in out, err
