"""The fuzz suite for results files: a mutated ``results.json`` is read exactly or refused naming the file.

One small benchmark (the expert and the random policy on two ``iid`` episodes) writes a
real ``results.json`` once; each example mutates it (:mod:`mutations`: wrong types,
absurd numbers, deleted and unknown keys, deep nesting, mangled bytes) or swaps it for a
file of another kind (a FIFO, a folder, a link to a device). Then:

- :func:`~training.evaluation.results.read_results` returns records that pass the
  schema, or raises :class:`ResultsError` naming the file; never another exception and
  never a hang (every example runs under an alarm);
- ``run_benchmark(..., resume=True)`` on that folder either refuses it (bad input: the
  file is left byte for byte as it was) or finishes with every record it read still in
  the file: a record it did not understand is never dropped.
"""

from __future__ import annotations

import gzip
import json
import os
import shutil
import tempfile
from pathlib import Path

import pytest
from cli_run import SAFETY_TIMEOUT_S
from hang import hang_guard
from hypothesis import given, settings
from hypothesis import strategies as st
from mutations import file_bytes, mutated, to_json_text
from test_fuzz_inputs import fuzz

from fetchcarry_env.errors import InputError
from training.evaluation.results import (
    MAX_RESULTS_BYTES,
    RESULTS,
    RESULTS_GZIP,
    ResultsError,
    encode_results,
    read_results,
    write_results,
)
from training.evaluation.runner import run_benchmark

HANG_SECONDS = SAFETY_TIMEOUT_S  # an example still running after this is a hang (a resumed run may plan one)
DEADLINE = None  # no per-example time bound: a loaded machine would break it; HANG_SECONDS stops a hang
BENCHMARK = {"policies": ["random"], "split": "iid", "episodes": 2}


@pytest.fixture(scope="module")
def finished(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder holding the results of a finished small benchmark."""
    out = tmp_path_factory.mktemp("benchmark")
    run_benchmark(**BENCHMARK, out=out)
    return out


def _copy(finished: Path) -> Path:
    folder = Path(tempfile.mkdtemp(dir=finished.parent)) / "out"
    shutil.copytree(finished, folder)
    return folder


def _mutate(data: st.DataObject, file: Path) -> None:
    document = json.loads(file.read_text())
    mutant = data.draw(mutated(document, max_mutations=3))
    file.write_bytes(data.draw(file_bytes(to_json_text(mutant))))


def _records_or_refusal(file: Path) -> list[dict] | None:
    """The records ``read_results`` reads, or None after a :class:`ResultsError` that names the file."""
    try:
        return read_results(file)
    except ResultsError as error:
        message = str(error)
        assert str(file) in message and len(message) < 2_000, message
        return None


@settings(fuzz(200), deadline=DEADLINE)
@given(data=st.data())
def test_fuzz_a_mutated_results_file_is_read_or_refused_naming_it(finished, data):
    folder = _copy(finished)
    _mutate(data, folder / RESULTS)
    with hang_guard(HANG_SECONDS, "reading a results file"):
        records = _records_or_refusal(folder / RESULTS)
    for record in records or ():
        assert isinstance(record["success"], bool) and isinstance(record["seed"], int), record
    shutil.rmtree(folder.parent)


@settings(fuzz(30), deadline=DEADLINE)
@given(data=st.data())
def test_fuzz_a_resumed_benchmark_keeps_every_record_it_read_or_leaves_the_file(finished, data):
    folder = _copy(finished)
    file = folder / RESULTS
    _mutate(data, file)
    before = file.read_bytes()
    with hang_guard(HANG_SECONDS, "reading a results file"):
        records = _records_or_refusal(file)
        try:
            run_benchmark(**BENCHMARK, out=folder, resume=True)
        except InputError:
            assert records is None, "a file read without complaint was refused on resume"
            assert file.read_bytes() == before, "a refused results file was changed"
            shutil.rmtree(folder.parent)
            return
    assert records is not None, "a results file refused by read_results was taken on resume"
    after = [json.dumps(record, sort_keys=True) for record in read_results(file)]
    for record in records:  # a record of this run may be replaced by a new one, never silently lost
        key = (record["policy"], record["split"], record["seed"])
        same_task = [r for r in read_results(file) if (r["policy"], r["split"], r["seed"]) == key]
        assert json.dumps(record, sort_keys=True) in after or same_task, record
    shutil.rmtree(folder.parent)


@pytest.mark.parametrize("kind", ["fifo", "folder", "device", "empty"])
def test_a_results_file_of_another_kind_is_refused_naming_it(finished, kind: str) -> None:
    folder = _copy(finished)
    file = folder / RESULTS
    file.unlink()
    if kind == "fifo":
        os.mkfifo(file)
    elif kind == "folder":
        file.mkdir()
    elif kind == "device":
        file.symlink_to("/dev/zero")
    else:
        file.write_bytes(b"")
    with hang_guard(HANG_SECONDS, "reading a results file"):
        assert _records_or_refusal(file) is None


def test_a_gzip_results_file_reads_as_its_plain_text_and_a_bomb_is_refused_unexpanded(finished) -> None:
    folder = _copy(finished)
    records = read_results(folder / RESULTS)
    write_results(folder / RESULTS_GZIP, records)
    assert read_results(folder / RESULTS_GZIP) == records
    assert encode_results(records, compressed=True) == (folder / RESULTS_GZIP).read_bytes()  # no time stamp
    whole = (folder / RESULTS_GZIP).read_bytes()
    bomb = gzip.compress(b" " * (MAX_RESULTS_BYTES + 1), mtime=0)  # 256 MB of blanks in about 250 kB
    cases = {
        "cut short": whole[: len(whole) // 2],
        "followed by other data": whole + b"more",
        "broken": whole[:10] + bytes(len(whole) - 10),
        "more than": bomb,
    }
    for problem, data in cases.items():
        (folder / RESULTS_GZIP).write_bytes(data)
        with hang_guard(HANG_SECONDS, "reading a gzip results file"), pytest.raises(ResultsError, match=problem):
            read_results(folder / RESULTS_GZIP)
