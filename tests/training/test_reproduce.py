"""``fetchcarry reproduce``: the published table end to end at the smoke budget, its resume, its bad input."""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
from dataclasses import replace
from pathlib import Path

import pytest

from fetchcarry_env.errors import InputError
from fetchcarry_env.observation import Capacity
from tests.cli_run import run
from training.cli import main
from training.evaluation.leaderboard import merge_folders
from training.evaluation.recheck import differences, wall_clock_bound
from training.evaluation.results import read_results, write_results
from training.evaluation.splits import get_split
from training.reproduce import SMOKE, pipeline
from training.reproduce.budgets import FULL
from training.reproduce.pipeline import SETTINGS_FILE, ReproduceError, check_settings, training_jobs
from training.reproduce.table import REFERENCES, baselines
from training.reproduce.weights import weights_digest

SPLITS = (
    "iid-v2:test",
    "more-objects-v2:test",
    "layouts-v3:test",
    "push-required-v2:test",
    "objects-v2:test",
    "apartment-v2:test",
    "perturbed-v2:test",
)
MAIN = ("bc-mlp", "bc-set", "dagger", "dagger-aimed", "ppo-scratch", "ppo-bc")


@pytest.fixture(scope="module")
def smoke(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One smoke reproduction (1 training seed, 2 workers), made once for the module; its folder."""

    out = tmp_path_factory.mktemp("reproduce") / "table"
    assert main(["reproduce", "--out", str(out), "--seeds", "1", "--budget", "smoke", "--no-progress"]) == 0
    return out


def test_smoke_writes_every_baseline_on_every_split(smoke: Path) -> None:
    out = smoke
    summary = (out / "summary.md").read_text()
    for split in SPLITS:
        assert f"## {split}" in summary
    for name in (*REFERENCES, *MAIN):
        assert f"| {name} |" in summary
    assert "Per scenario source (iid-v2:test)" in summary and "| baseline | basic | push |" in summary
    records = read_results(out / "results.json")  # schema 2, checked: every cost is minus its return
    assert json.loads((out / "results.json").read_text())["schema_version"] == 2
    assert [r["cost"] for r in records] == pytest.approx([-r["return"] for r in records])
    assert all(0 <= r["travel"] <= r["cost"] for r in records)
    seen = {(r["baseline"], r["split"]) for r in records}
    for split in SPLITS:
        for name in (*REFERENCES, *MAIN):
            assert (name, split) in seen, (name, split)
    assert {r["training_seed"] for r in records if r["baseline"] in MAIN} == {0}
    assert {r["training_seed"] for r in records if r["baseline"] in REFERENCES} == {None}
    # the demonstrations curve's runs are measured on iid only
    curve = {r["split"] for r in records if r["baseline"].startswith("bc-mlp-n")}
    assert curve == {"iid-v2:test"}
    for plot in ("splits.png", "ppo_curves.png", "demonstrations.png"):
        assert (out / plot).stat().st_size > 1000, plot
    for job in training_jobs(out, 1, SMOKE):
        config = json.loads((Path(job.out) / "config.json").read_text())
        assert config["complete"] and config["kind"] == job.kind
    # the expert dataset stays in the reproduction's folder, and the caller's Minari folder is left alone
    assert (out / "datasets" / "fetchcarry" / "training-phases-v0").is_dir()
    assert not any(Path(os.environ["MINARI_DATASETS_PATH"]).iterdir())


def test_a_second_call_skips_every_finished_stage(smoke: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "copy"
    shutil.copytree(smoke, out)
    # what a Ctrl-C during the benchmark of iid, before that of layouts, during one curve run would have left
    iid = out / "benchmark" / "iid" / "results.json"
    write_results(iid, read_results(iid)[:-3])
    shutil.rmtree(out / "benchmark" / "layouts")
    shutil.rmtree(out / "runs" / "bc-mlp-n2-s0")
    # and a run trained again with other weights since it was benchmarked on push-required
    digests = out / "benchmark" / "push-required" / "weights.json"
    digests.write_text(json.dumps({**json.loads(digests.read_text()), "bc-set-s0": "other weights"}))
    weights = {p: p.stat().st_mtime_ns for p in (out / "runs").glob("*/model.pt")}
    status, stdout, _ = run(capsys, "reproduce", "--out", out, "--seeds", 1, "--budget", "smoke", "--workers", 1,
                            "--no-progress")  # fmt: skip
    assert status == 0
    assert "[1/4] datasets: already complete" in stdout
    assert f"{len(training_jobs(out, 1, SMOKE)) - 1} already complete" in stdout
    assert "training 1/1: bc-mlp-n2-s0 done" in stdout  # retrained to the same weights: its episodes stay
    assert all(p.stat().st_mtime_ns == mtime for p, mtime in weights.items())  # nothing finished trained again
    n = SMOKE.episodes
    everywhere = 4 + sum(len(b.runs) for b in baselines(1, SMOKE) if not b.label.startswith("bc-mlp-n"))
    assert f"benchmark iid-v2:test: {(everywhere + 1) * n} episodes ({(everywhere + 1) * n - 3} resumed)" in stdout
    assert "benchmark more-objects-v2:test: already complete" in stdout
    assert f"benchmark layouts-v3:test: {everywhere * n} episodes (0 resumed)" in stdout
    assert f"benchmark push-required-v2:test: {everywhere * n} episodes ({(everywhere - 1) * n} resumed)" in stdout
    records = read_results(out / "results.json")
    assert len(records) == len(read_results(smoke / "results.json"))
    assert {(r["baseline"], r["split"]) for r in records} == {
        (r["baseline"], r["split"]) for r in read_results(smoke / "results.json")
    }


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--seeds", "0"], "expected a positive number"),
        (["--budget", "huge"], "invalid choice"),
        (["--workers", "x"], "expected a whole number"),
    ],
)
def test_bad_numbers_exit_2(capsys, tmp_path: Path, argv: list[str], message: str) -> None:
    status, _, err = run(capsys, "reproduce", "--out", tmp_path / "t", *argv)
    assert status == 2 and message in err


def test_a_folder_of_another_budget_or_of_other_files_is_refused(capsys, smoke: Path, tmp_path) -> None:
    out = tmp_path / "copy"
    shutil.copytree(smoke, out)
    status, _, err = run(capsys, "reproduce", "--out", out, "--seeds", 1, "--no-progress")  # the full budget
    assert status == 2 and "another budget (smoke)" in err
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    status, _, err = run(capsys, "reproduce", "--out", tmp_path / "other", "--budget", "smoke", "--no-progress")
    assert status == 2 and "not an empty folder" in err
    assert (tmp_path / "other" / "notes.txt").read_text() == "mine"


def test_ctrl_c_exits_130_and_says_how_to_continue(capsys, tmp_path: Path, monkeypatch) -> None:
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(pipeline, "_stage_datasets", interrupted)
    before = os.environ["MINARI_DATASETS_PATH"]
    status, _, err = run(capsys, "reproduce", "--out", tmp_path / "t", "--budget", "smoke", "--no-progress")
    assert status == 130 and "run the same command again to continue" in err
    assert os.environ["MINARI_DATASETS_PATH"] == before


def test_an_internal_error_is_exit_3_not_bad_input(capsys, tmp_path: Path, monkeypatch) -> None:
    # a plotting ValueError inside the pipeline once printed as bad input (exit 2)

    def broken(*args, **kwargs):
        raise ValueError("'yerr' must not contain negative values")

    monkeypatch.setattr(pipeline, "_stage_datasets", broken)
    status, _, err = run(capsys, "reproduce", "--out", tmp_path / "t", "--budget", "smoke", "--no-progress")
    assert status == 3 and "yerr" in err


def test_a_folder_made_before_a_budget_field_existed_is_still_the_same_budget(tmp_path: Path) -> None:
    out = tmp_path / "table"
    check_settings(out, 1, SMOKE)
    saved = json.loads((out / SETTINGS_FILE).read_text())
    for name in ("aimed_iterations", "aimed_families"):
        del saved["budget"][name]  # written before these fields existed
    (out / SETTINGS_FILE).write_text(json.dumps(saved))
    made_before = replace(SMOKE, aimed_iterations=0)  # what such a folder was made with: the fields' defaults
    check_settings(out, 1, made_before)
    aimed = replace(made_before, aimed_iterations=1)
    (out / SETTINGS_FILE).write_text(json.dumps(saved))
    with pytest.raises(ReproduceError, match="another budget"):
        check_settings(out, 1, aimed)


def test_the_budget_aims_a_second_dagger_from_the_dataset(tmp_path: Path) -> None:
    options = FULL.aimed_options("some/dataset-v0")
    assert options.dataset == "some/dataset-v0" and options.demonstrations == FULL.demonstrations
    assert options.learner_families == ("push", "multi-2") and options.epochs == FULL.bc_epochs
    assert FULL.dagger_options().dataset is None and FULL.dagger_options().learner_families == ()
    names = [job.name for job in training_jobs(tmp_path, 2, FULL)]
    assert "dagger-aimed-s0" in names and "dagger-aimed-s1" in names
    none = replace(FULL, aimed_iterations=0)
    assert not any(job.name.startswith("dagger-aimed") for job in training_jobs(tmp_path, 2, none))
    assert "dagger-aimed" not in [b.label for b in baselines(2, none)]
    with pytest.raises(ValueError, match="aimed_iterations"):
        replace(FULL, aimed_iterations=-1)


def test_with_two_seeds_or_more_the_aimed_runs_make_an_ensemble(tmp_path: Path) -> None:
    jobs = {job.name: job for job in training_jobs(tmp_path, 3, FULL)}
    ensemble = jobs["dagger-aimed-ensemble"]
    assert ensemble.kind == "ensemble" and ensemble.needs == ("dagger-aimed-s0", "dagger-aimed-s1", "dagger-aimed-s2")
    assert ensemble.members == tuple(jobs[name].out for name in ensemble.needs)
    (row,) = [b for b in baselines(3, FULL) if b.label == "dagger-aimed-ensemble"]
    assert row.runs == ("dagger-aimed-ensemble",) and not row.per_seed
    assert "dagger-aimed-ensemble" not in {job.name for job in training_jobs(tmp_path, 1, FULL)}
    assert "dagger-aimed-ensemble" not in [b.label for b in baselines(1, FULL)]


def test_the_summary_names_its_commit_and_the_table_publishes_under_50_mb(smoke: Path, tmp_path: Path) -> None:
    from training.reproduce.publish import MAX_PUBLISHED_BYTES, PublishError, commit_line, publish, record_commit

    summary = (smoke / "summary.md").read_text()
    settings = json.loads((smoke / SETTINGS_FILE).read_text())
    (commit,) = settings["commits"]
    assert commit_line([commit]) in summary and commit[:7] in summary
    out = tmp_path / "copy"
    shutil.copytree(smoke, out)
    assert record_commit(out, "f" * 40) == [commit, "f" * 40]  # a call at another commit: the summary says so
    assert "across 2 commits" in commit_line([commit, "f" * 40])
    copied = publish(out, tmp_path / "published")
    assert 0 < copied["bytes"] < MAX_PUBLISHED_BYTES
    published = tmp_path / "published"
    assert read_results(published / "results.json.gz") == read_results(out / "results.json")  # gzip: 1/6 the size
    assert not (published / "results.json").exists()
    assert len(merge_folders([published])) == len(read_results(out / "results.json"))  # leaderboard finds the .gz
    assert (published / "runs" / "bc-mlp-s0" / "config.json").is_file()
    assert any(run.name.startswith("bc-mlp-n") for run in (published / "runs").iterdir())  # every run's config
    runs_with_weights = {Path(w).parts[1] for w in copied["weights"]}
    assert runs_with_weights >= {"bc-mlp-s0", "dagger-s0"}  # one seed: the best
    assert not any(run.startswith("bc-mlp-n") for run in runs_with_weights)  # not the demonstrations curve's
    assert not (published / "datasets").exists()
    with pytest.raises(PublishError, match="no finished table"):
        publish(tmp_path / "published" / "runs", tmp_path / "nowhere")


def test_the_table_capacity_holds_every_split_so_flat_networks_act_on_all() -> None:
    for budget in (FULL, SMOKE):
        room = Capacity.parse(budget.capacity)
        for split in budget.splits:
            assert room.covers(get_split(split).capacity), (budget.name, split)
        assert pipeline.split_episodes("apartment", budget) <= get_split("apartment").episodes


def test_a_budget_with_repeated_splits_is_refused() -> None:
    with pytest.raises(InputError, match="distinct"):
        replace(SMOKE, splits=("iid", "iid"))


@pytest.mark.skipif(importlib.util.find_spec("ray") is None, reason="Ray is not installed")
def test_on_ray_the_smoke_gives_the_pools_records_and_weights(smoke: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "on-ray"
    status, stdout, _ = run(capsys, "reproduce", "--out", out, "--seeds", 1, "--budget", "smoke", "--backend", "ray",
                            "--workers", 2, "--no-progress")  # fmt: skip
    assert status == 0 and "[4/4] report" in stdout
    pool, ray = read_results(smoke / "results.json"), read_results(out / "results.json")
    assert [(r["policy"], r["split"], r["seed"]) for r in ray] == [(r["policy"], r["split"], r["seed"]) for r in pool]
    # every field but the timings; the expert's own run only where its 10 s safety stop cannot have bound (in either)
    exempt = [wall_clock_bound(a) or wall_clock_bound(b) for a, b in zip(pool, ray, strict=True)]
    assert any(exempt) and {a["policy"] for a, bound in zip(pool, exempt, strict=True) if bound} == {"expert"}
    for a, b, bound in zip(pool, ray, exempt, strict=True):
        assert bound or differences(a, b) == {}, (a["policy"], a["split"], a["seed"])
    for job in training_jobs(smoke, 1, SMOKE):  # the same weights, tensor for tensor
        name = Path(job.out).name
        assert weights_digest(Path(job.out) / "model.pt") == weights_digest(out / "runs" / name / "model.pt"), name
    digests = json.loads((out / "benchmark" / "iid" / "weights.json").read_text())
    assert digests == json.loads((smoke / "benchmark" / "iid" / "weights.json").read_text())
    assert all(d.startswith("tensors:") for d in digests.values())


def test_benchmark_check_reproduces_a_runs_records_and_finds_a_tampered_one(smoke: Path, tmp_path, capsys) -> None:
    runs = [smoke / "runs" / name for name in ("bc-mlp-s0", "ppo-bc-s0", "dagger-aimed-s0")]
    argv = ["--policies", *runs, "greedy", "--split", "iid", "push-required", "--workers", 2, "--no-progress"]
    status, out, _ = run(capsys, "benchmark", "--check", smoke / "results.json", *argv)
    assert status == 0, out
    others = len(read_results(smoke / "results.json")) - 16
    assert f"16 of 16 records identical (timings aside: decision_ms, mask_ms, step_ms); {others} records" in out
    records = read_results(smoke / "results.json")
    (k,) = [k for k, r in enumerate(records) if r["policy"] == "bc-mlp-s0" and r["seed"] == 1010500001]
    flipped = {"success": not records[k]["success"], "delivered": records[k]["objects"]}  # a success delivers all
    costlier = {"cost": records[k]["cost"] + 1.0, "return": records[k]["return"] - 1.0}  # still minus each other
    records[k] = {**records[k], **flipped, **costlier}
    write_results(tmp_path / "results.json", records)
    status, out, _ = run(capsys, "benchmark", "--check", tmp_path / "results.json", *argv)
    assert status == 1
    assert "15 of 16 records identical" in out
    assert "bc-mlp-s0 push-required-v2:test seed 1010500001: success" in out and "; cost" in out
