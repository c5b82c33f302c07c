"""``fetchcarry references --invariant RESULTS...``: no episode earns more than the proven reference on its scenario."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.cli_run import run
from training.cli import main
from training.evaluation.references import part_references
from training.evaluation.results import read_results, write_results

EPISODES = 3  # iid-v2:test episodes 0-2: basic, push, corridor
POLICIES = ("expert", "random-phases", "greedy")  # the benchmark runs the first two with any policy


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``fetchcarry benchmark --policies greedy --split iid --episodes 3``: a results folder of the three policies."""
    out = tmp_path_factory.mktemp("invariant") / "iid"
    argv = ["benchmark", "--policies", "greedy", "--split", "iid", "--episodes", EPISODES, "--no-progress"]
    assert main([str(a) for a in (*argv, "--out", out)]) == 0
    return out


def test_the_policies_of_a_results_folder_keep_the_invariant(folder: Path, capsys) -> None:
    records = read_results(folder / "results.json")
    assert sorted({r["policy"] for r in records}) == sorted(POLICIES)
    assert {r["split"] for r in records} == {"iid-v2:test"}
    assert all(r["proven"] for r in part_references("iid-v2:test")[:EPISODES])  # every record is compared
    status, out, _ = run(capsys, "references", "--invariant", folder)
    assert status == 0
    compared = len(POLICIES) * EPISODES
    assert f"0 of {compared} episodes with a proven reference earn more than it ({compared} records read)" in out


def test_a_record_that_earns_more_than_its_reference_is_named_and_exits_1(folder: Path, tmp_path: Path, capsys):
    records = read_results(folder / "results.json")
    (k,) = [k for k, r in enumerate(records) if r["policy"] == "greedy" and r["source"] == "push"]
    reference = part_references("iid-v2:test")[1]
    assert reference["seed"] == records[k]["seed"] and reference["proven"]
    earned = reference["return"] + 1.0  # one more than the proven optimum: a task cost of one less
    cost = -earned
    records[k] = {**records[k], "return": earned, "cost": cost, "travel": min(records[k]["travel"], cost)}
    write_results(tmp_path / "results.json", records)  # still schema-valid: its cost is minus its return
    assert read_results(tmp_path / "results.json")[k]["return"] == earned
    status, out, _ = run(capsys, "references", "--invariant", tmp_path / "results.json", folder)
    assert status == 1
    line = f"greedy iid-v2:test seed {reference['seed']}: return {earned:.3f} in {records[k]['phases']} steps above"
    assert line in out and f"the proven reference's {reference['return']:.3f} in {reference['phases']}" in out
    compared = 2 * len(POLICIES) * EPISODES  # both files are read: the copy and the folder it came from
    assert f"1 of {compared} episodes with a proven reference earn more than it" in out
