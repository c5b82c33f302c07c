"""Results files bounded in what they parse and name, their records checked against the schema and each other.

A hostile ``results.json`` (or ``.json.gz``) must give a short refusal with exit 2,
never a ``MemoryError``, a numpy warning or a run that does not end: records are read
one at a time and checked as they come (the first bad record stops the read), the
number of records, the JSON values they hold, the characters of one record and the
splits, policies and scenarios a file names are capped, a record's figures must agree
with each other, and no episode may be recorded twice.
"""

from __future__ import annotations

import gzip
import hashlib
import json
import re
import resource
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from tests.cli_run import run
from training.evaluation import results
from training.evaluation.results import MAX_RESULTS_BYTES, ResultsError, read_results, write_results

ROOT = Path(__file__).resolve().parents[2]  # the checkout: where the child process runs
SAFETY_TIMEOUT_S = 600  # seconds: stops a child that would hang; a guard, not a speed bound
PUBLISHED = ROOT / "docs" / "benchmarks" / "published" / "results.json.gz"
MEMORY_BOUND_BYTES = 200 * 2**20  # far below the 3.4 GB the unbounded reader took; the bounded one needs a few MB
ADDRESS_SPACE_LIMIT = 3 * 2**30  # the child's whole address space: the unbounded reader hits it instead of the machine

# The child process: the fetchcarry command line with tracemalloc's peak (bytes) printed last on stderr.
PEAK_CHILD = """
import sys, tracemalloc
from training.cli import main
tracemalloc.start()
status = main(sys.argv[1:])
print(f"peak bytes {tracemalloc.get_traced_memory()[1]}", file=sys.stderr)
sys.exit(status)
"""


def _limit_address_space() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE_LIMIT, ADDRESS_SPACE_LIMIT))


def run_child(*argv: object) -> tuple[int, str, int]:
    """``fetchcarry argv...`` in a subprocess with a bounded address space: (status, stderr, peak traced bytes)."""
    done = subprocess.run(
        [sys.executable, "-c", PEAK_CHILD, *map(str, argv)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=SAFETY_TIMEOUT_S,
        preexec_fn=_limit_address_space,
    )
    lines = done.stderr.strip().splitlines()
    peak = int(lines[-1].split()[-1]) if lines and lines[-1].startswith("peak bytes") else -1
    return done.returncode, done.stderr, peak


def record(policy: str = "me", seed: int = 0, split: str = "scenarios:mine", **fields: Any) -> dict[str, Any]:
    """A well-formed record of one episode (a success, 1 object, 3 phases), ``fields`` changed."""
    return {
        "policy": policy,
        "scenario": f"s{seed}",
        "split": split,
        "source": "a.json",
        "seed": seed,
        "digest": hashlib.sha256(str(seed).encode()).hexdigest(),
        "success": True,
        "delivered": 1,
        "objects": 1,
        "cost": 5.0,
        "expert_cost": 5.0,
        "return": 5.0,
        "phases": 3,
        "pushes": 0,
        "invalid_actions": 0,
        "contacts": 0,
        "decision_ms": 1.0,
        "mask_ms": 0.5,
        **fields,
    }


def table(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """``records`` with expert rows on the same scenarios in front: a table leaderboard and compare can rank."""
    seeds = dict.fromkeys((r["split"], r["seed"]) for r in records)
    return [*(record("expert", seed, split) for split, seed in seeds), *records]


def folder_of(tmp_path: Path, records: list[dict[str, Any]], name: str = "bench") -> Path:
    """A results folder holding ``records`` as written by the benchmark (no check on the way)."""
    folder = tmp_path / name
    folder.mkdir()
    write_results(folder / "results.json", records)
    return folder


# ------------------------------------------------------------------ memory: the objects parsed, not only the bytes
def test_a_gzip_of_empty_records_is_refused_at_record_0_in_bounded_memory(tmp_path: Path) -> None:
    """260 kB of gzip inflating to almost 256 MB of ``{},``: millions of dicts before; now record 0 is refused."""
    folder = tmp_path / "bomb"
    folder.mkdir()
    count = (MAX_RESULTS_BYTES - 64) // 3
    text = b'{"records":[' + b"{}," * (count - 1) + b"{}]}"
    assert len(text) <= MAX_RESULTS_BYTES
    (folder / "results.json.gz").write_bytes(gzip.compress(text, compresslevel=9, mtime=0))
    assert (folder / "results.json.gz").stat().st_size < 400_000
    for argv in (["leaderboard", folder], ["compare", "a", "b", "--results", folder]):
        status, err, peak = run_child(*argv)
        assert status == 2, err
        assert "MemoryError" not in err and "Traceback" not in err, err
        assert f"{folder / 'results.json.gz'}: record 0 has no 'policy'" in err, err
        assert 0 < peak < MEMORY_BOUND_BYTES, (peak, err)


def test_a_record_longer_than_its_cap_is_refused_before_it_is_parsed_whole(tmp_path: Path) -> None:
    """One record holding a 100 MB list: refused at its cap of characters, in a few MB of memory."""
    folder = tmp_path / "long"
    folder.mkdir()
    head = json.dumps({"schema_version": 1, "records": [record(), record(seed=1)]})[:-2]
    text = head.encode() + b', {"extra": [' + b"[]," * 30_000_000 + b"[]]}]}"
    (folder / "results.json").write_bytes(text)
    status, err, peak = run_child("leaderboard", folder)
    assert status == 2, err
    assert f"record 2 is more than {results.MAX_RECORD_CHARS:,} characters" in err, err
    assert 0 < peak < MEMORY_BOUND_BYTES, (peak, err)


def test_more_records_than_the_cap_are_refused_naming_it(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(results, "MAX_RECORDS", 5)
    folder = folder_of(tmp_path, [record(seed=k) for k in range(6)])
    assert len(read_results(folder_of(tmp_path, [record(seed=k) for k in range(5)], "five") / "results.json")) == 5
    with pytest.raises(ResultsError, match=r"results\.json: more than 5 records \(record 5\)"):
        read_results(folder / "results.json")


def test_records_holding_more_json_values_than_the_cap_are_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Extra fields are kept, but the values of every record together are capped (containers, members, items)."""
    monkeypatch.setattr(results, "MAX_VALUES", 200)
    fine = [record(seed=k, extra=[]) for k in range(4)]
    assert len(read_results(folder_of(tmp_path, fine, "fine") / "results.json")) == 4
    heavy = [record(seed=k, extra=[[]] * 20) for k in range(4)]
    with pytest.raises(ResultsError, match=r"more than 200 JSON values by record [1-3]"):
        read_results(folder_of(tmp_path, heavy) / "results.json")


def test_a_bad_record_is_refused_before_the_records_after_it_are_read(tmp_path: Path) -> None:
    """A record that breaks the schema stops the read: what follows it (here broken JSON) is never reached."""
    text = json.dumps({"schema_version": 1, "records": [record(), record(seed=1, success="yes")]})
    (tmp_path / "results.json").write_text(text[:-2] + ", {not json")
    with pytest.raises(ResultsError, match=r"record 1 .*'success' = \"yes\""):
        read_results(tmp_path / "results.json")


# ------------------------------------------------------------------ what a file may name
def test_a_file_of_far_more_splits_than_the_cap_is_refused_naming_it(tmp_path: Path, capsys) -> None:
    """100,000 splits of one record each: the leaderboard ran for minutes; now exit 2 at the cap."""
    records = [record(seed=k, split=f"scenarios:s{k}") for k in range(100_000)]
    folder = folder_of(tmp_path, records)
    for argv in (["leaderboard", folder], ["compare", "me", "expert", "--results", folder]):
        status, _, err = run(capsys, *argv)
        assert status == 2, err
        assert f"more than {results.MAX_SPLITS} splits" in err and "record 64" in err, err


@pytest.mark.parametrize(
    ("name", "make", "message"),
    [
        ("MAX_POLICIES", lambda k: record(f"p{k}", seed=0), "more than 4 policies"),
        ("MAX_PAIRS", lambda k: record(f"p{k % 3}", seed=k, split=f"scenarios:{k // 3}"), "more than 4 pairs"),
        ("MAX_SPLIT_SCENARIOS", lambda k: record(seed=k), r"more than 4 scenarios on \"scenarios:mine\""),
    ],
)
def test_more_policies_pairs_or_scenarios_than_their_caps_are_refused(
    name: str, make, message: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(results, name, 4)
    with pytest.raises(ResultsError, match=message):
        read_results(folder_of(tmp_path, [make(k) for k in range(12)]) / "results.json")


def test_the_published_results_still_rank_and_compare(tmp_path: Path, capsys) -> None:
    folder = tmp_path / "published"
    folder.mkdir()
    shutil.copy(PUBLISHED, folder / "results.json.gz")
    status, out, err = run(capsys, "leaderboard", folder, "--json")
    assert status == 0, err
    board = json.loads(out)
    assert len(board) == 7 and sum(entry["episodes"] for entries in board.values() for entry in entries) == 42_470
    status, out, err = run(capsys, "compare", "dagger", "bc-mlp", "--results", folder)
    assert status == 0 and len(out.splitlines()) == 7, err


# ------------------------------------------------------------------ records checked against each other
def test_a_record_given_twice_is_refused_naming_both(tmp_path: Path, capsys) -> None:
    """Every record twice doubled n and narrowed the intervals; now the second copy is refused."""
    records = table([record(seed=k) for k in range(3)])
    folder = folder_of(tmp_path, [*records, records[4]])
    for argv in (["leaderboard", folder], ["compare", "me", "expert", "--results", folder]):
        status, _, err = run(capsys, *argv)
        assert status == 2, err
        assert "records 4 and 6 are the same episode" in err and "results.json" in err, err


def test_two_labels_of_one_method_and_training_seed_on_one_scenario_are_the_same_episode(tmp_path: Path) -> None:
    """``bc-s0`` and a record of method ``bc``, training seed 0 are pooled as one run: one episode per scenario."""
    records = [record("bc-s0", seed=1), record("mine", seed=1, baseline="bc", training_seed=0)]
    with pytest.raises(ResultsError, match=r"records 0 and 1 are the same episode \(method \"bc\", training seed 0"):
        read_results(folder_of(tmp_path, records) / "results.json")
    other_seed = [record("bc-s0", seed=1), record("mine", seed=1, baseline="bc", training_seed=1)]
    assert len(read_results(folder_of(tmp_path, other_seed, "fine") / "results.json")) == 2


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"success": True, "delivered": 0}, r"'success' = true but delivers 0 of 1 objects"),
        ({"delivered": 2}, r"delivers 2 of 1 objects"),
        ({"cost": -1.0}, r"'cost' = -1\.0, which is negative"),
        ({"cost": 1e308}, r"'cost' = 1e\+308, more than its 3 phases can travel"),
        ({"phases": 0}, r"'cost' = 5\.0, more than its 0 phases can travel"),
        ({"expert_cost": 1e308}, r"'expert_cost' = 1e\+308, more than"),
        ({"return": -1e308}, r"'return' = -1e\+308, more in size than"),
        ({"decision_ms": 1e308}, r"'decision_ms' = 1e\+308, more than"),
        ({"step_ms": -2.0}, r"'step_ms' = -2\.0, which is negative"),
        ({"objects": 2**40, "success": False}, r"'objects' = 1099511627776, more than"),
        ({"training_seed": -1}, r"'training_seed' = -1, which is negative"),
        ({"digest": "x"}, r"'digest' = \"x\", which is not 64 hexadecimal digits"),
        ({"references": "ABC"}, r"'references' = \"ABC\", which is not 64 hexadecimal digits"),
    ],
)
def test_a_record_whose_figures_disagree_is_refused_naming_the_record_and_field(
    fields: dict[str, Any], message: str, tmp_path: Path, capsys
) -> None:
    folder = folder_of(tmp_path, table([record(seed=0), record(seed=1), record(seed=2, **fields)]))
    status, _, err = run(capsys, "leaderboard", folder)
    assert status == 2, err
    assert f'{folder / "results.json"}: record 5 (policy "me"' in err, err
    assert re.search(message, err), err


def test_absurd_figures_give_no_numpy_warning(tmp_path: Path) -> None:
    """Costs of 1e308 printed numpy's overflow warnings; now they are refused, and stderr holds the refusal only."""
    huge = [record(seed=k, cost=1e308, phases=3, **{"return": -1e308}) for k in range(3)]
    folder = folder_of(tmp_path, table(huge))
    for argv in (["leaderboard", folder], ["compare", "me", "expert", "--results", folder]):
        status, err, _ = run_child(*argv)
        assert status == 2, err
        assert "Warning" not in err and "overflow" not in err, err
        assert "record 3" in err and "'cost' = 1e+308" in err, err


def test_a_reference_cost_too_small_for_a_ratio_gives_no_ratio_and_no_warning(tmp_path: Path) -> None:
    """A reference that travelled less than a millimetre: no cost ratio of 1e300 (whose sums overflow)."""
    tiny = [record("expert", k, cost=1e-305) for k in range(3)]
    mine = [record(seed=k, cost=1e6, phases=2000) for k in range(3)]
    folder = folder_of(tmp_path, [*tiny, *mine])
    status, err, _ = run_child("leaderboard", folder, "--json")
    assert status == 0, err
    assert "Warning" not in err and "overflow" not in err, err
