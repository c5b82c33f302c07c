"""``fetchcarry leaderboard`` and ``fetchcarry compare``: a user's factory policy among others, refusals."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from training.cli import main
from training.evaluation.results import read_results, write_results

USER_MODULE = """
import numpy as np


class FirstAllowed:
    def predict(self, observation, state=None, episode_start=None, deterministic=False, action_masks=None):
        return int(np.flatnonzero(action_masks)[0]), state


def make_policy(env):
    return FirstAllowed()
"""  # the ten-line example of docs/protocol.md


@pytest.fixture(scope="module")
def folders(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("board")
    (root / "my_policies.py").write_text(USER_MODULE)
    sys.path.insert(0, str(root))
    try:
        mine, theirs = root / "mine", root / "theirs"
        common = ["--split", "iid", "--episodes", "4", "--no-progress"]
        assert main(["benchmark", "--policies", "my_policies:make_policy", *common, "--out", str(mine)]) == 0
        assert main(["benchmark", "--policies", "greedy", *common, "--out", str(theirs)]) == 0
    finally:
        sys.path.remove(str(root))
    # a third folder: a method of two training seeds (its records made from the greedy's, one seed failing one)
    seeds = root / "seeds"
    greedy = [r for r in read_results(theirs / "results.json") if r["policy"] == "greedy"]
    made = [
        {**r, "policy": f"made-s{k}", "success": r["success"] and not (k == 1 and i == 0)}
        for k in range(2)
        for i, r in enumerate(greedy)
    ]
    seeds.mkdir()
    write_results(seeds / "results.json", made)
    return {"mine": mine, "theirs": theirs, "seeds": seeds, "root": root}


def test_a_users_factory_is_merged_with_two_other_folders(folders: dict, capsys: pytest.CaptureFixture) -> None:
    argv = ["leaderboard", str(folders["mine"]), str(folders["theirs"]), str(folders["seeds"]), "--json"]
    assert main(argv) == 0
    board = json.loads(capsys.readouterr().out)
    entries = board["iid-v2:test"]
    methods = [e["policy"] for e in entries]
    assert set(methods) == {"expert", "random-phases", "my_policies:make_policy", "greedy", "made"}
    assert [e["rank"] for e in entries] == list(range(1, len(entries) + 1))
    assert [e["success"] for e in entries] == sorted((e["success"] for e in entries), reverse=True)
    made = next(e for e in entries if e["policy"] == "made")
    assert made["seeds"] == 2 and made["episodes"] == 8 and made["scenarios"] == 4
    assert made["left_out"] == 0 and made["against_first"]["scenarios"] == 4
    assert entries[0]["against_first"] is None
    assert main(argv[:-1]) == 0
    text = capsys.readouterr().out
    assert "my_policies:make_policy" in text and "random-phases" in text and "paired bootstrap" in text


def test_compare_is_paired_on_the_same_scenarios(folders: dict, capsys: pytest.CaptureFixture) -> None:
    argv = ["compare", "made", "greedy", "--results", str(folders["theirs"]), str(folders["seeds"]), "--json"]
    assert main(argv) == 0
    (result,) = json.loads(capsys.readouterr().out)
    # seed 1 fails the first scenario greedy solved: -1/2 on one scenario of four, the others equal
    greedy = [r for r in read_results(folders["theirs"] / "results.json") if r["policy"] == "greedy"]
    expected = -0.5 / 4 if greedy[0]["success"] else 0.0
    assert result["scenarios"] == 4 and result["success_diff"] == pytest.approx(expected)
    assert result["success_low"] <= result["success_diff"] <= result["success_high"] <= 0
    assert result["cost_diff"] == pytest.approx(0.0)  # the same costs where both solved
    assert result["seeds"] == 1 and result["seed_wins"] == 0  # greedy's single run is one observation, not two
    assert main(["compare", "nobody", "greedy", "--results", str(folders["theirs"])]) == 2


def _copy(folders: dict, name: str, change: dict) -> Path:
    out = folders["root"] / name
    out.mkdir(exist_ok=True)
    records = [
        {**r, **change, "policy": f"{r['policy']}-{name}"}
        for r in read_results(folders["mine"] / "results.json")
        if r["policy"] == "my_policies:make_policy"
    ]
    write_results(out / "results.json", records)
    return out


def test_different_versions_references_or_a_method_twice_are_refused(folders: dict, capsys) -> None:
    v0 = _copy(folders, "v0", {"split": "iid-v0", "references": None})
    other = _copy(folders, "other", {"references": "0" * 64})
    assert main(["leaderboard", str(folders["mine"]), str(v0)]) == 2
    assert "different versions of iid: iid-v2" in capsys.readouterr().err
    assert main(["leaderboard", str(folders["theirs"]), str(other)]) == 2
    assert "different references" in capsys.readouterr().err
    assert main(["leaderboard", str(folders["mine"]), str(folders["mine"])]) == 2
    assert "in both" in capsys.readouterr().err
    assert main(["leaderboard", str(folders["root"] / "nothing-here")]) == 2


def test_methods_are_ranked_on_the_scenarios_they_all_ran_and_the_table_says_so(folders: dict, capsys) -> None:
    fewer = folders["root"] / "fewer"
    fewer.mkdir(exist_ok=True)
    greedy = [r for r in read_results(folders["theirs"] / "results.json") if r["policy"] == "greedy"]
    write_results(fewer / "results.json", [{**r, "policy": "half"} for r in greedy[:2]])  # 2 of the 4 scenarios
    assert main(["leaderboard", str(folders["theirs"]), str(fewer), "--json"]) == 0
    entries = json.loads(capsys.readouterr().out)["iid-v2:test"]
    assert {e["scenarios"] for e in entries} == {2}  # every row on the same two scenarios
    assert {e["policy"]: e["left_out"] for e in entries} == {"expert": 2, "random-phases": 2, "greedy": 2, "half": 0}
    assert main(["leaderboard", str(folders["theirs"]), str(fewer)]) == 0
    assert (
        "Ranked on the 2 scenarios every method ran; episodes on other scenarios left out: " in capsys.readouterr().out
    )
    elsewhere = folders["root"] / "elsewhere"
    elsewhere.mkdir(exist_ok=True)
    write_results(elsewhere / "results.json", [{**r, "policy": "moved", "seed": r["seed"] + 10**6} for r in greedy])
    assert main(["leaderboard", str(folders["theirs"]), str(elsewhere)]) == 2
    assert "no scenario was run by every method" in capsys.readouterr().err


def test_a_folder_of_scenarios_is_tabled_by_family_not_by_file() -> None:
    from training.evaluation.report import family_of, source_table

    def record(policy: str, source: str, seed: int, success: bool) -> dict:
        return {"policy": policy, "scenario": source, "split": "scenarios:mine", "source": source, "seed": seed,
                "digest": None, "success": success, "delivered": int(success), "objects": 1, "cost": 5.0,
                "expert_cost": 5.0, "return": 5.0, "phases": 3, "pushes": 0, "invalid_actions": 0, "contacts": 0,
                "decision_ms": 1.0, "mask_ms": 0.0}  # fmt: skip

    files = ["objects-1-0001.json", "objects-1-0002.json", "objects-2-0001.json", "push_basic.json"]
    records = [record(p, f, k, p == "expert" or k == 0) for p in ("expert", "me") for k, f in enumerate(files)]
    lines = source_table(records, "scenarios:mine", "caption")
    assert lines[2] == "| policy | objects-1 | objects-2 | push_basic |"
    assert lines[5].startswith("| me | 50% [")
    assert family_of({"source": "x.json", "family": "given"}) == "given"


def _records(policy: str, split: str, successes: list[bool]) -> list[dict]:
    return [
        {"policy": policy, "split": split, "seed": s, "digest": f"d{s}", "success": ok}
        for s, ok in enumerate(successes)
    ]


def test_the_view_across_splits_is_rliables_on_the_seeds_success_rates() -> None:
    from scipy.stats import trim_mean

    from training.evaluation.across import across_markdown, across_splits, success_matrices

    rates = {  # per method, per split: its seeds' successes over four scenarios
        "greedy": {"iid-v2:test": [[1, 1, 1, 1]], "layouts-v3:test": [[1, 1, 1, 0]]},
        "bc": {"iid-v2:test": [[1, 1, 0, 0], [1, 1, 1, 0], [1, 1, 1, 1]], "layouts-v3:test": [[1, 0, 0, 0]] * 3},
    }
    records = [
        r
        for method, by_split in rates.items()
        for split, seeds in by_split.items()
        for k, outcomes in enumerate(seeds)
        for r in _records(method if method == "greedy" else f"{method}-s{k}", split, [bool(x) for x in outcomes])
    ]
    records += _records("only-iid", "iid-v2:test", [True] * 4) + _records("greedy", "iid-v2:test", [True])[4:]
    splits, matrices, left_out = success_matrices(records)
    assert splits == ("iid-v2:test", "layouts-v3:test") and left_out == ["only-iid"]
    np.testing.assert_allclose(matrices["bc"], [[0.5, 0.25], [0.75, 0.25], [1.0, 0.25]])
    np.testing.assert_allclose(matrices["greedy"], [[1.0, 0.75]])
    across = across_splits(records)
    assert across.reference == "greedy" and [row.method for row in across.rows] == ["greedy", "bc"]
    bc = across.rows[1]
    assert bc.iqm == pytest.approx(trim_mean([0.5, 0.25, 0.75, 0.25, 1.0, 0.25], 0.25)) and bc.runs == 3
    assert bc.improvement == pytest.approx((0.5 * (1 / 3) + 0) / 2)  # iid: one seed ties greedy's 1.0; layouts: none
    assert bc.iqm_low <= bc.iqm <= bc.iqm_high and bc.iqm_low < bc.iqm_high  # three seeds: a spread
    assert bc.profile == pytest.approx((2 / 6, 1 / 6, 1 / 6))  # above 50 %: 0.75 and 1.0; above 75 and 90 %: 1.0
    text = "\n".join(across_markdown(across))
    assert (
        "## Across splits (2: iid-v2:test, layouts-v3:test)" in text
        and "Left out (not run on every split): only-iid" in text
    )
    assert across_splits([r for r in records if r["split"] == "iid-v2:test"]) is None  # one split: no view


def test_the_leaderboard_of_one_split_has_no_view_across(folders: dict, capsys: pytest.CaptureFixture) -> None:
    assert main(["leaderboard", str(folders["theirs"])]) == 0
    out = capsys.readouterr().out
    assert "## iid-v2:test" in out and "Across splits" not in out
