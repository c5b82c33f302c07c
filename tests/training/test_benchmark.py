"""The benchmark: splits, metrics, the records and reports it writes, and ``fetchcarry benchmark``."""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from fetchcarry_env.families import EXTENT, FAMILIES, HELD_OUT_FAMILIES, turn_quarter
from fetchcarry_env.kinematics import WAIT_COST
from fetchcarry_env.scenario import Scenario
from training import benchmark
from training.cli import main
from training.evaluation import runner
from training.evaluation.results import read_results
from training.evaluation.splits import SPLIT_BLOCK, TRAINING_FAMILIES

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"
KEYS = {
    "policy": str,
    "scenario": str,
    "split": str,
    "source": str,
    "seed": int,
    "digest": str,
    "success": bool,
    "delivered": int,
    "objects": int,
    "cost": float,
    "travel": float,
    "return": float,
    "phases": int,
    "pushes": int,
    "invalid_actions": int,
    "contacts": int,
    "decision_ms": float,
    "mask_ms": float,
}


def _untimed(records: list[dict]) -> list[dict]:
    return [{k: v for k, v in r.items() if k not in ("decision_ms", "mask_ms", "step_ms")} for r in records]


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``fetchcarry benchmark --policies expert random --split iid --episodes 2`` (basic and push)."""
    out = tmp_path_factory.mktemp("bench") / "iid"
    argv = ["benchmark", "--policies", "expert", "random", "--split", "iid", "--episodes", "2", "--no-progress"]
    assert main([*argv, "--out", str(out)]) == 0
    return out


# ------------------------------------------------------------------ end to end
def test_expert_and_random_end_to_end(tiny: Path):
    records = read_results(tiny / "results.json")
    assert [(r["policy"], r["source"]) for r in records] == list(
        itertools.product(["expert", "random-phases", "random"], ["basic", "push"])
    )
    for record in records:
        for key, kind in KEYS.items():
            assert isinstance(record[key], kind), key
        assert record["split"] == "iid-v2:test"
        assert record["seed"] >= benchmark.EVAL_SEED_BASE
        assert 0 <= record["delivered"] <= record["objects"]
        assert record["decision_ms"] > 0
        assert record["cost"] == pytest.approx(-record["return"]) and record["travel"] <= record["cost"]  # task cost
    expert = [r for r in records if r["policy"] == "expert"]
    assert all(r["success"] and r["invalid_actions"] == 0 for r in expert)
    # the expert plays the proven optimum its reference holds: the task cost of the reference's plan
    assert [r["cost"] for r in expert] == pytest.approx([r["expert_cost"] for r in expert], rel=1e-9)
    assert expert[1]["pushes"] >= 1  # the push family's clutter stands on the goal
    random = [r for r in records if r["policy"] == "random"]
    assert [r["expert_cost"] for r in random] == [r["expert_cost"] for r in expert]
    # the task cost: travel plus W1 for every object not at its goal after each step; the expert's one object
    # reaches its goal by its last step, the random policy's is not there after its last
    assert [r["cost"] for r in expert] == pytest.approx([r["travel"] + WAIT_COST * (r["phases"] - 1) for r in expert])
    assert all(r["cost"] >= r["travel"] + WAIT_COST * (r["objects"] - r["delivered"]) > r["travel"] for r in random)
    summary = (tiny / "summary.md").read_text()
    assert "| expert | iid-v2:test | 2 | 100.0% [" in summary and "| random | iid-v2:test | 2 |" in summary
    assert "0 for doing nothing, 100 for the reference" in summary and "fixed reference" in summary
    assert "Per scenario source (iid-v2:test)" in summary and "| policy | basic | push |" in summary
    assert "| expert | 100% [21%, 100%] (1.00) | 100% [21%, 100%] (1.00) |" in summary  # one episode each
    assert "| random | 0% [0%, 79%] (-) | 0% [0%, 79%] (-) |" in summary
    assert (tiny / "splits.png").read_bytes()[:4] == b"\x89PNG"


def test_same_command_same_results_except_timing(tiny: Path, tmp_path: Path):
    argv = ["benchmark", "--policies", "expert", "random", "--split", "iid", "--episodes", "2", "--no-progress"]
    assert main([*argv, "--out", str(tmp_path)]) == 0
    first = read_results(tiny / "results.json")
    again = read_results(tmp_path / "results.json")
    assert _untimed(first) == _untimed(again)


def test_workers_give_the_same_results_and_json_rows(tiny: Path, tmp_path: Path, capsys: pytest.CaptureFixture):
    argv = ["benchmark", "--policies", "expert", "random", "--split", "iid", "--episodes", "2", "--no-progress"]
    assert main([*argv, "--workers", "2", "--json", "--out", str(tmp_path)]) == 0
    first = read_results(tiny / "results.json")
    again = read_results(tmp_path / "results.json")
    assert _untimed(first) == _untimed(again)
    rows = json.loads(capsys.readouterr().out)
    assert [r["policy"] for r in rows] == ["expert", "random-phases", "random"]
    assert (rows[0]["success"], rows[2]["success"]) == (1.0, 0.0)
    assert rows[0]["cost_ratio"] == pytest.approx(1.0, rel=1e-9) and rows[2]["cost_ratio"] is None
    assert rows[0]["score"] == pytest.approx(100.0, rel=1e-9)
    assert rows[2]["score"] <= 0.0  # every episode failed: none above doing nothing


def test_scenario_folder(tmp_path: Path):
    folder = tmp_path / "mine"
    folder.mkdir()
    shutil.copy(EXAMPLE, folder / "a_example.json")
    turn_quarter(Scenario.load(EXAMPLE)).save(folder / "b_turned.json")
    out = tmp_path / "out"
    argv = ["benchmark", "--policies", "expert", "--scenarios", str(folder), "--out", str(out), "--no-progress"]
    assert main(argv) == 0
    records = read_results(out / "results.json")
    files = ["a_example.json", "b_turned.json"]
    assert [(r["policy"], r["source"]) for r in records] == list(itertools.product(["expert", "random-phases"], files))
    assert {r["split"] for r in records} == {"scenarios:mine"}
    assert all(r["success"] for r in records[:2])
    # The turned scenario costs the expert what the original does, up to the lattice: the world is isotropic.
    assert records[1]["cost"] == pytest.approx(records[0]["cost"], rel=0.05)


def test_run_folder_acts_through_the_candidate_phases(tmp_path: Path):
    bc = pytest.importorskip("training.learners.bc")
    from fetchcarry_env.observation import Capacity

    demonstrations = bc.record_demonstrations("basic", range(3))
    bc.train_bc(demonstrations, bc.BCConfig(epochs=2, hidden=16), Capacity(), out=tmp_path / "bc-tiny")
    import torch

    threads = torch.get_num_threads()
    report = benchmark.run_benchmark([str(tmp_path / "bc-tiny")], split="iid", episodes=1, out=tmp_path / "out")
    assert torch.get_num_threads() == threads  # one thread while deciding, given back afterwards
    names = [r["policy"] for r in report.records]
    assert names == ["expert", "random-phases", "bc-tiny"]
    learned = report.records[2]
    assert learned["invalid_actions"] == 0  # the candidate masks are exact: a masked policy is never refused
    assert [row.policy for row in report.rows] == names
    shutil.copytree(tmp_path / "bc-tiny", tmp_path / "expert")  # a run folder may not pose as a reference
    with pytest.raises(benchmark.BenchmarkError, match="may not be named"):
        runner.with_references([str(tmp_path / "expert")])


def test_interrupt_keeps_finished_records_and_exits_130(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    calls = []
    real = runner.run_task

    def interrupted_third(task):
        calls.append(task)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(task)

    monkeypatch.setattr(runner, "run_task", interrupted_third)
    argv = ["benchmark", "--policies", "random", "--split", "iid", "--episodes", "2", "--no-progress"]
    assert main([*argv, "--out", str(tmp_path)]) == 130
    records = read_results(tmp_path / "results.json")
    assert [r["policy"] for r in records] == ["expert", "expert"]
    assert (tmp_path / "summary.md").exists()
    # --resume keeps those two and runs only the random policy's episodes
    calls.clear()
    monkeypatch.setattr(runner, "run_task", lambda task: calls.append(task) or real(task))
    assert main([*argv, "--resume", "--out", str(tmp_path)]) == 0
    assert [task[0].name for task in calls] == ["random-phases", "random-phases", "random", "random"]
    records = read_results(tmp_path / "results.json")
    assert [r["policy"] for r in records] == ["expert", "expert", "random-phases", "random-phases", "random", "random"]
    assert all(r["expert_cost"] is not None for r in records)


def test_resume_keeps_the_records_of_other_policies_and_splits(tiny: Path, tmp_path: Path):
    shutil.copy(tiny / "results.json", tmp_path / "results.json")
    before = read_results(tmp_path / "results.json")
    benchmark.run_benchmark(["random"], split="layouts", episodes=1, out=tmp_path, resume=True)
    records = read_results(tmp_path / "results.json")
    assert [(r["policy"], r["split"]) for r in records[: -len(before)]] == [
        ("expert", "layouts-v3:test"),
        ("random-phases", "layouts-v3:test"),
        ("random", "layouts-v3:test"),
    ]
    assert records[-len(before) :] == before
    summary = (tmp_path / "summary.md").read_text()
    assert "Benchmark: layouts-v3:test, iid-v2:test" in summary  # this run's split first, then the file's others


# ------------------------------------------------------------------ bad input
def _broken_run(tmp_path: Path) -> Path:
    run = tmp_path / "broken"
    run.mkdir()
    (run / "config.json").write_text("{not json")
    return run


@pytest.mark.parametrize(
    "change",
    [
        ["--policies", "expert", "no-such-policy", "--split", "iid"],
        ["--policies", "expert", "runs/missing", "--split", "iid"],
        ["--policies", "expert", "--split", "no-such-split"],
        ["--policies", "expert", "--split", "iid-v99"],
        ["--policies", "expert", "--scenarios", "no/such/folder"],
        ["--policies", "expert", "--split", "iid", "--episodes", "0"],
        ["--policies", "expert", "--split", "iid", "--scenarios", "."],
        ["--policies", "BROKEN", "--split", "iid"],
        ["--policies", "expert", "--scenarios", "EMPTY"],
    ],
)
def test_bad_input_exits_2(change, tmp_path: Path, capsys: pytest.CaptureFixture):
    broken, empty = _broken_run(tmp_path), tmp_path / "empty"
    empty.mkdir()
    named = {"BROKEN": str(broken), "EMPTY": str(empty)}
    argv = ["benchmark", *[named.get(a, a) for a in change]]
    assert _status([*argv, "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert "Traceback" not in error and error.strip()
    assert not (tmp_path / "out" / "results.json").exists()


def _status(argv: list[str]) -> int:
    """The exit status of ``fetchcarry argv`` (argparse's own errors raise ``SystemExit``)."""
    try:
        return main(argv)
    except SystemExit as error:
        return int(error.code)


def test_a_policy_without_room_for_the_objects_is_refused():
    small = benchmark.PolicySpec("two-slots", "phases", run="runs/x", env_options={"capacity": {"objects": 2}})
    with pytest.raises(benchmark.BenchmarkError, match="two-slots cannot act in multi-3"):
        runner.check_fits([small], benchmark.split_scenarios("more-objects", 2))
    runner.check_fits([small], benchmark.split_scenarios("iid", 4))  # one and two objects fit


def test_a_room_larger_than_the_families_floor_is_played_on_its_own(tmp_path: Path):
    """An 8 x 4 m room, which plan, validate, rollout and gym.make take, was refused by benchmark --scenarios."""
    data = json.loads(EXAMPLE.read_text())
    data["area"] = {"min": [-1.0, -0.5], "max": [7.0, 3.5]}  # 8 x 4 m: wider than the families' 7 m
    data["tables"][1].update(min=[3.7, 2.3], max=[4.3, 2.9])
    data["objects"][0]["goal"] = [4.0, 2.6]
    data["clutter"][0].update(min=[3.9, 2.5], max=[4.1, 2.7])
    data["obstacles"] = []
    (tmp_path / "wide.json").write_text(json.dumps(data))
    items = benchmark.folder_scenarios(tmp_path)
    assert items[0].floor == {"scenario": items[0].scenario}
    out = tmp_path / "out"
    argv = ["benchmark", "--policies", "expert", "--scenarios", str(tmp_path), "--out", str(out), "--no-progress"]
    assert main(argv) == 0
    assert all(r["success"] for r in read_results(out / "results.json") if r["policy"] == "expert")


# ------------------------------------------------------------------ metrics
def test_wilson_interval_by_hand():
    # p = 0.8, n = 10, z = 1.96: centre (0.8 + z²/20) / (1 + z²/10), half z sqrt(0.016 + z²/400) / (1 + z²/10)
    low, high = benchmark.wilson(8, 10)
    assert (low, high) == pytest.approx((0.490157, 0.943319), abs=1e-6)
    assert benchmark.wilson(0, 4) == pytest.approx((0.0, 0.4899000), abs=1e-6)  # z²/(n + z²) = 3.8416/7.8416
    assert all(math.isnan(v) for v in benchmark.wilson(0, 0))
    assert benchmark.wilson(9, 10) == pytest.approx((0.596, 0.982), abs=1e-3)
    assert benchmark.wilson(0, 10)[0] == 0.0


def test_wilson_interval_contains_the_rate_at_0_and_100_percent():
    # rounding once put 100 % of 6 episodes above the interval's top, and the plots refused a negative error bar
    for n in range(1, 400):
        for wins in (0, n):
            low, high = benchmark.wilson(wins, n)
            assert low <= wins / n <= high


def test_spl_by_hand():
    assert benchmark.spl(True, 12.0, 10.0) == pytest.approx(10 / 12)
    assert benchmark.spl(True, 9.0, 10.0) == 1.0  # never above 1, even below the expert's cost
    assert benchmark.spl(False, 10.0, 10.0) == 0.0


def _record(policy: str, seed: int, success: bool, cost: float, ret: float, **extra) -> dict:
    base = {"policy": policy, "split": "s", "seed": seed, "success": success, "cost": cost, "return": ret}
    base.update(delivered=int(success), objects=1, phases=4, pushes=0, invalid_actions=0, contacts=0, decision_ms=1.0)
    return {**base, **extra}


def test_summary_by_hand():
    records = [
        _record("expert", 1, True, 10.0, 0.0),
        _record("expert", 2, True, 5.0, 5.0),
        _record("random", 1, False, 30.0, -40.0, invalid_actions=3),
        _record("random", 2, False, 20.0, -20.0, invalid_actions=1),
        _record("learned", 1, True, 12.0, -2.0),
        _record("learned", 2, False, 8.0, -10.0, contacts=2),
    ]
    benchmark.fill_expert_costs(records)
    rows = {row.policy: row for row in benchmark.summarise(records)}
    learned = rows["learned"]
    assert learned.success == 0.5
    assert learned.cost_ratio == pytest.approx(1.2)  # only the solved seed: 12 / 10
    assert learned.spl == pytest.approx((10 / 12 + 0) / 2)
    # doing nothing: -500 (one object, 50 phases); the failure counts -500, the success its -2; expert 0 and 5
    assert learned.score == pytest.approx(100 * ((-2 + 500) + 0) / ((0 + 500) + (5 + 500)))
    assert rows["expert"].score == pytest.approx(100.0) and rows["random"].score == pytest.approx(0.0)
    assert learned.contacts == 1.0 and rows["random"].invalid_actions == 2.0
    assert learned.expert_phases == 4.0
    assert "| learned | s | 2 | 50.0% [" in benchmark.summary_markdown(list(rows.values()))


def test_plots_of_learning_curves_and_demonstrations(tmp_path: Path):
    run = tmp_path / "run"
    run.mkdir()
    (run / "metrics.csv").write_text("epoch,loss,accuracy,seconds\n1,2.0,0.3,0.1\n2,1.0,0.6,0.2\n")
    assert benchmark.plot_learning_curve(run, tmp_path / "curve.png").read_bytes()[:4] == b"\x89PNG"
    assert benchmark.plot_learning_curve(run, tmp_path / "time.png", ["loss"], x="seconds").exists()
    with pytest.raises(ValueError, match="no column"):
        benchmark.plot_learning_curve(run, tmp_path / "bad.png", x="steps")
    records = [{"policy": "bc", "demonstrations": n, "success": k < n // 10} for n in (10, 30, 100) for k in range(10)]
    assert benchmark.plot_demonstrations(records, tmp_path / "demos.png").read_bytes()[:4] == b"\x89PNG"


# ------------------------------------------------------------------ splits
PAIRED_ON_PURPOSE = {  # splits that draw another split's seeds, so that their episodes pair with its
    f"perturbed-{factor}-v2:{part}": f"perturbed-v2:{part}"
    for factor in ("layout", "distractors", "physics")
    for part in ("dev", "test")
}


def test_split_seeds_are_disjoint_from_training_seeds_and_from_each_other():
    seen: dict[int, set[int]] = {}  # version number -> its seeds
    for split in benchmark.SPLITS.values():
        seeds = {item.seed for item in benchmark.split_scenarios(split, 10)}
        block = split.offset - split.offset % SPLIT_BLOCK
        assert min(seeds) >= benchmark.EVAL_SEED_BASE + split.offset
        assert max(seeds) < benchmark.EVAL_SEED_BASE + block + SPLIT_BLOCK  # its own block
        if split.name in PAIRED_ON_PURPOSE:  # the same seeds as the split it pairs with, and only those
            assert split.offset == benchmark.SPLITS[PAIRED_ON_PURPOSE[split.name]].offset
            continue
        assert not seeds & seen.get(split.version_number, set())  # within a version: disjoint
        seen.setdefault(split.version_number, set()).update(seeds)
    # v1's dev parts are v0's scenarios (recipes were tuned on them); its test parts met nothing before
    test = {
        s
        for split in benchmark.SPLITS.values()
        if split.part == "test"
        for s in range(split.seed(0), split.seed(299) + 1)
    }
    assert not test & seen[0]
    # The learning checks hold out seeds from 100,000 and datasets count up from 0: far below.
    assert benchmark.EVAL_SEED_BASE > 100_000 * 1_000


def test_split_names_and_versions():
    assert benchmark.get_split("iid").name == "iid-v2:test" and benchmark.get_split("iid:dev").name == "iid-v2:dev"
    assert benchmark.get_split("more-objects-v0").sources[0].name == "multi-3"
    iid = benchmark.split_scenarios("iid", 8)
    assert [item.source for item in iid] == list(TRAINING_FAMILIES) * 2
    assert [s.scenario for s in benchmark.split_scenarios("iid-v1:dev", 8)] == [
        s.scenario for s in benchmark.split_scenarios("iid-v0", 8)
    ]
    assert [s.source for s in benchmark.split_scenarios("iid:dev", 8)] == list(TRAINING_FAMILIES) * 2
    older = {s.scenario.name for v in ("iid-v0", "iid-v1:test") for s in benchmark.split_scenarios(v, 8)}
    assert not older & {s.scenario.name for s in benchmark.split_scenarios("iid:dev", 8)}  # fresh seeds
    assert [len(item.scenario.objects) for item in benchmark.split_scenarios("more-objects", 4)] == [3, 4, 3, 4]


def test_a_split_version_never_changes():
    # Digests of the first three scenarios of each split when it was published: a change needs a new version.
    published = {
        "iid-v0": "fc34ea4f9f628d50",
        "more-objects-v0": "44b025e7ea45ee92",
        "layouts-v0": "1f1698736be96064",
        "push-required-v0": "56744d90abfa7852",
    }
    assert set(published) == {s for s in benchmark.SPLITS if s.endswith("-v0")}  # v1: every digest, references
    for name, digest in published.items():
        h = hashlib.sha256()
        for item in benchmark.split_scenarios(name, 3):
            h.update(json.dumps([item.seed, item.source, item.scenario.to_dict()], sort_keys=True).encode())
        assert h.hexdigest()[:16] == digest, name


def test_several_splits_in_one_run(tmp_path: Path):
    report = benchmark.run_benchmark(["random"], split=["layouts", "push-required"], episodes=1, out=tmp_path)
    assert [(r["policy"], r["split"]) for r in report.records] == [
        ("expert", "layouts-v3:test"),
        ("expert", "push-required-v2:test"),
        ("random-phases", "layouts-v3:test"),
        ("random-phases", "push-required-v2:test"),
        ("random", "layouts-v3:test"),
        ("random", "push-required-v2:test"),
    ]
    assert [(row.policy, row.split) for row in report.rows] == [(r["policy"], r["split"]) for r in report.records]
    assert "Benchmark: layouts-v3:test, push-required-v2:test" in (tmp_path / "summary.md").read_text()


@pytest.mark.parametrize(("split", "newest"), [("iid-v1", "iid-v2:test"), ("layouts-v2:dev", "layouts-v3:dev")])
def test_a_v1_split_is_refused_naming_the_split_to_use(split: str, newest: str, tmp_path: Path, capsys) -> None:
    """Its references were made under release 0.2's task: no score against them, exit 2 before any episode."""
    argv = ["benchmark", "--policies", "random", "--split", split, "--episodes", "1", "--no-progress"]
    assert _status([*argv, "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert f"benchmark {newest} instead" in error and "release 0.2" in error and "Traceback" not in error
    assert not (tmp_path / "out" / "results.json").exists()


def test_push_required_scenarios_have_clutter_on_a_goal():
    for item in benchmark.split_scenarios("push-required", 15):
        goals = [(o.goal, o.radius) for o in item.scenario.objects]
        assert any(c.rect.overlaps_disc(g, r) for c in item.scenario.clutter for g, r in goals), item.source


def test_layouts_are_held_out_of_training():
    # Every training family starts the robot in the bottom-left room; the held-out layouts are turned
    # a quarter turn, so the robot starts in the bottom-right one: no training draw looks like them.
    for name in (*TRAINING_FAMILIES, "multi", "mixed", "training"):
        for seed in range(30):
            assert FAMILIES[name].sample(np.random.default_rng(seed)).robot.start[0] < 1.0, (name, seed)
    layouts = benchmark.split_scenarios("layouts-v1", 20)
    assert {item.source for item in layouts} == set(HELD_OUT_FAMILIES)
    for item in layouts:
        assert item.scenario.robot.start[0] > 4.0
        assert EXTENT.contains_rect(item.scenario.area)


def test_training_families_still_draw_the_same_scenarios():
    # Digests of seeds 0-2 of each family taken before the held-out layouts were added.
    before = {
        "basic": "10a1c436b96b03ff",
        "push": "1df547cccf6aaf0e",
        "corridor": "2a7c0b7a3a7974cd",
        "multi": "3f41cafd66baf292",
        "multi-2": "0519662623e95ff2",
        "multi-3": "20095c1d6bd0cf57",
        "multi-4": "ac895ffcf4ced897",
        "mixed": "168b602dee85f815",
    }
    for name, digest in before.items():
        h = hashlib.sha256()
        for seed in range(3):
            h.update(json.dumps(FAMILIES[name].sample(np.random.default_rng(seed)).to_dict(), sort_keys=True).encode())
        assert h.hexdigest()[:16] == digest, name


def test_turn_quarter_four_times_is_the_identity():
    scenario = FAMILIES["push"].sample(np.random.default_rng(3))
    turned = scenario
    for _ in range(4):
        turned = turn_quarter(turned)
    assert turned.robot.heading == scenario.robot.heading
    assert turned.robot.start == pytest.approx(scenario.robot.start)
    assert turned.tables[1].rect.min_x == pytest.approx(scenario.tables[1].rect.min_x)


def test_unknown_policy_lists_what_is_available():
    with pytest.raises(benchmark.BenchmarkError, match="expert, random"):
        benchmark.resolve("no-such-policy")
    assert "greedy" in benchmark.FACTORIES  # wired; resolved only where its module is installed


def test_every_policy_has_its_own_colour_and_the_plot_has_zero_bars_and_n(tmp_path: Path):
    from matplotlib.colors import to_hex

    from training.pictures.benchmark import policy_colours

    names = ["expert", "random-phases", "random", "greedy", "ppo-bc", *(f"method-{k}" for k in range(30))]
    colours = {to_hex(c) for c in policy_colours(names).values()}
    assert len(colours) == len(names)  # expert and ppo-bc once shared one
    records = [_record(p, s, p == "expert" or (p == "me" and s == 1), 5.0, 1.0, objects=1 + s % 2)
               for p in ("expert", "me", "never") for s in range(4)]  # fmt: skip
    benchmark.fill_expert_costs(records)
    rows = benchmark.summarise(records)
    assert benchmark.plot_splits(rows, tmp_path / "s.png").read_bytes()[:4] == b"\x89PNG"
    from training.pictures.benchmark import _caption

    assert _caption(rows).startswith("n = 4 episodes per bar")
