"""``results.json``: one writer per folder, resume by scenario digest, a schema that refuses a broken file."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import numpy as np
import pytest

from fetchcarry_env.families import get_family
from fetchcarry_env.scenario import Scenario
from tests.cli_run import run
from training import benchmark
from training.evaluation.results import (
    LOCK,
    SCHEMA_VERSION,
    ResultsLock,
    read_results,
    record_problem,
    scenario_digest,
)

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"


def _folder(path: Path, family: str, count: int, seed: int = 0, names: list[str] | None = None) -> Path:
    """``count`` scenarios of ``family`` as files ``a.json``, ``b.json``, ... (or ``names``) in ``path``."""
    path.mkdir(parents=True, exist_ok=True)
    for old in path.glob("*.json"):
        old.unlink()
    rng = np.random.default_rng(seed)
    for name in names or [f"{chr(ord('a') + k)}.json" for k in range(count)]:
        get_family(family).sample(rng).save(path / name)
    return path


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A valid results.json: expert and random on the example (schema 1)."""
    out = tmp_path_factory.mktemp("results")
    folder = out / "scenarios"
    folder.mkdir()
    (folder / "example.json").write_text(EXAMPLE.read_text())
    benchmark.run_benchmark(["random"], scenarios=folder, out=out / "bench")
    return out / "bench" / "results.json"


# ------------------------------------------------------------------ one writer per folder
def test_a_second_benchmark_on_the_same_folder_exits_2_naming_the_holder(
    saved: Path, tmp_path: Path, capsys: pytest.CaptureFixture
):
    out = tmp_path / "bench"
    out.mkdir()
    before = saved.read_text()
    (out / "results.json").write_text(before)
    scenarios = saved.parent.parent / "scenarios"
    with ResultsLock(out):  # another benchmark is writing here
        status, _, err = run(capsys, "benchmark", "--policies", "greedy", "--scenarios", scenarios, "--resume",
                             "--out", out, "--no-progress")  # fmt: skip
    assert status == 2
    assert f"another benchmark is writing to {out}" in err and f"process {os.getpid()}" in err
    assert (out / "results.json").read_text() == before  # the holder's records are untouched
    # the holder gone, the same command runs (the lock dies with its holder)
    status, _, _ = run(capsys, "benchmark", "--policies", "greedy", "--scenarios", scenarios, "--resume",
                       "--out", out, "--no-progress")  # fmt: skip
    assert status == 0
    assert [r["policy"] for r in read_results(out / "results.json")] == ["expert", "random-phases", "greedy", "random"]
    assert (out / LOCK).exists()


# ------------------------------------------------------------------ resume by digest
def test_resume_runs_again_the_scenarios_whose_files_changed(tmp_path: Path):
    folder = _folder(tmp_path / "cases", "basic", 3)
    out = tmp_path / "bench"
    first = benchmark.run_benchmark(["random"], scenarios=folder, out=out, resume=True)
    assert first.resumed == 0 and len(first.records) == 9  # expert, random-phases (the references) and random
    again = benchmark.run_benchmark(["random"], scenarios=folder, out=out, resume=True)
    assert again.resumed == 9  # nothing changed: nothing runs

    _folder(folder, "push", 3, seed=1)  # three push scenarios under the same names
    pushed = benchmark.run_benchmark(["random"], scenarios=folder, out=out, resume=True)
    assert pushed.resumed == 0
    digests = [scenario_digest(Scenario.load(folder / n)) for n in ("a.json", "b.json", "c.json")]
    records = read_results(out / "results.json")
    assert len(records) == 9  # the basic scenarios' records are replaced, not kept next to them
    assert [r["digest"] for r in records] == digests * 3
    assert all(r["source"] in ("a.json", "b.json", "c.json") for r in records)

    (folder / "0.json").write_text(EXAMPLE.read_text())  # a file in front: every index moves
    shifted = benchmark.run_benchmark(["random"], scenarios=folder, out=out, resume=True)
    assert shifted.resumed == 0 and len(read_results(out / "results.json")) == 12

    other = _folder(tmp_path / "elsewhere" / "cases", "corridor", 4, names=["0.json", "a.json", "b.json", "c.json"])
    elsewhere = benchmark.run_benchmark(["random"], scenarios=other, out=out, resume=True)
    assert elsewhere.resumed == 0  # another folder of the same name
    assert [r["digest"] for r in read_results(out / "results.json")][:4] == [
        scenario_digest(Scenario.load(other / n)) for n in ("0.json", "a.json", "b.json", "c.json")
    ]


def test_every_record_carries_its_scenario_digest(saved: Path):
    records = read_results(saved)
    assert {r["digest"] for r in records} == {scenario_digest(Scenario.load(EXAMPLE))}
    data = json.loads(saved.read_text())
    assert data["schema_version"] == SCHEMA_VERSION and isinstance(data["records"], list)


# ------------------------------------------------------------------ a hand-edited file
def _edited(saved: Path, tmp_path: Path, edit) -> Path:
    out = tmp_path / "bench"
    out.mkdir()
    data = json.loads(saved.read_text())
    other = {**data["records"][1], "policy": "someone-else"}
    data["records"].append(other)
    edit(data["records"])
    (out / "results.json").write_text(json.dumps(data))
    return out


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda rs: rs[0].pop("success"), r"record 0 \(policy \"expert\".*\) has no 'success'"),
        (lambda rs: rs[0].update(success="yes"), r"record 0 .*'success' = \"yes\", which is not true or false"),
        (
            lambda rs: rs[3].update(seed=float(rs[3]["seed"])),
            r"record 3 \(policy \"someone-else\".*'seed' = .*not an integer",
        ),
        (lambda rs: rs[1].update(cost=None), r"record 1 .*'cost' = null, which is not a number"),
        (lambda rs: rs[1].update(delivered=True), r"record 1 .*'delivered' = true"),
        (lambda rs: rs.append([1, 2]), r"record 4 is list, not an object"),
    ],
    ids=["no success", "success yes", "float seed of another policy", "null cost", "bool delivered", "not an object"],
)
def test_a_results_file_that_breaks_the_schema_is_refused_with_exit_2(
    edit, message: str, saved: Path, tmp_path: Path, capsys: pytest.CaptureFixture
):
    out = _edited(saved, tmp_path, edit)
    before = (out / "results.json").read_text()
    status, _, err = run(capsys, "benchmark", "--policies", "random", "--scenarios", saved.parent.parent / "scenarios",
                         "--resume", "--out", out, "--no-progress")  # fmt: skip
    assert status == 2, err
    assert str(out / "results.json") in err
    assert re.search(message, err), err
    assert (out / "results.json").read_text() == before  # nothing dropped, nothing written


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('{"schema_version": 99, "records": []}', "schema_version 99 is not one this version reads"),
        ('{"records": []}', "schema_version null"),
        ('{"schema_version": 1, "records": {}}', "'records' is not a list"),
        ('"results"', "not an object with 'schema_version'"),
        ("[{", "not valid JSON"),
    ],
)
def test_a_results_file_of_another_shape_is_refused(text: str, message: str, tmp_path: Path):
    (tmp_path / "results.json").write_text(text)
    with pytest.raises(benchmark.BenchmarkError, match=message):
        read_results(tmp_path / "results.json")


def test_the_earlier_plain_list_is_read_and_its_episodes_run_again(saved: Path, tmp_path: Path):
    """A schema-0 file (a list, no digests): its episodes run again, other policies' records stay."""
    out = tmp_path / "bench"
    out.mkdir()
    records = [{k: v for k, v in r.items() if k != "digest"} for r in read_results(saved)]
    legacy = [*records, {**records[1], "policy": "someone-else"}]
    (out / "results.json").write_text(json.dumps(legacy))
    assert [r["digest"] for r in read_results(out / "results.json")] == [None] * 4
    report = benchmark.run_benchmark(["random"], scenarios=saved.parent.parent / "scenarios", out=out, resume=True)
    assert report.resumed == 0
    after = read_results(out / "results.json")
    assert [(r["policy"], r["digest"] is None) for r in after] == [
        ("expert", False),
        ("random-phases", False),
        ("random", False),
        ("someone-else", True),
    ]


def test_record_problem_by_hand(saved: Path):
    record = read_results(saved)[0]
    assert record_problem(record) is None
    assert record_problem({**record, "extra": [1]}) is None  # other fields are kept as they are
    cost = round(record["cost"])
    assert record_problem({**record, "cost": cost, "return": -cost, "travel": 0}) is None  # an integer is a number
    assert "not minus its task cost" in record_problem({**record, "return": record["return"] + 1.0})
    assert "above its task cost" in record_problem({**record, "travel": record["cost"] + 1.0})
    assert "negative" in record_problem({**record, "pushes": -1})
    assert "delivers 2 of 1" in record_problem({**record, "delivered": 2})
    assert "not a number" in record_problem({**record, "return": float("nan")})
