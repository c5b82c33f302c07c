"""Hardening (issue 8, sections 1-3): no code from a data file, exit statuses, datasets never corrupted.

Every test here reproduces one attack or fault of the issue through the command line
(in-process through ``training.cli.main``, or a subprocess where signals are involved). A subprocess test
waits for a state, never for a number of seconds (``cli_run.SAFETY_TIMEOUT_S`` only stops a hang).
"""

from __future__ import annotations

import json
import os
import shutil as shutil_module
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from cli_run import ROOT, SAFETY_TIMEOUT_S, bench, cli_process, finish, run, signal_while_frozen, wait_for
from gymnasium.envs.registration import EnvSpec

import expert.planner
import training.cli.benchmark
import training.cli.exits
import training.cli.planning
import training.data.datasets
import training.data.generate
import training.data.staging
import training.evaluation.expert
from expert.plans import Plan
from training.data.datasets import UnknownEnvError, dataset_path, recover_replaced, trusted_env_spec
from training.data.generate import DATASET_TIME_LIMIT, EpisodeSource, GenerationConfig, run_indexed_episode
from training.data.staging import DatasetLock, Staging, StagingError

DATASET_ID = "fetchcarry/hard-v0"


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


# ---------------------------------------------------------------------------- 2. interrupts and exit statuses
EXAMPLE = ROOT / "examples" / "push_basic.json"


def interrupted_solve(*args, **kwargs):
    """What ``expert.plan`` does when Ctrl-C arrives during a SCIP solve: raise ``KeyboardInterrupt``."""
    raise KeyboardInterrupt


def test_ctrl_c_during_a_solve_of_plan_writes_no_plan_and_exits_130(capsys, monkeypatch, tmp_path: Path) -> None:
    monkeypatch.setattr(expert.planner, "plan", interrupted_solve)
    output = tmp_path / "out.plan.json"
    status, _, err = run(capsys, "plan", EXAMPLE, "-o", output)
    assert status == 130 and "interrupted" in err
    assert not output.exists()


def test_ctrl_c_during_a_solve_of_generate_records_no_episode(capsys, monkeypatch) -> None:
    """One worker: the first episode is staged, Ctrl-C arrives in the second episode's solve."""

    real_plan = expert.planner.plan
    calls = {"n": 0}

    def plan_then_interrupt(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] > 1:
            raise KeyboardInterrupt
        return real_plan(*args, **kwargs)

    monkeypatch.setattr(expert.planner, "plan", plan_then_interrupt)
    argv = ["generate", "--scenario", EXAMPLE, "--episodes", "3", "--dataset-id", DATASET_ID, "--no-progress"]
    status, _, err = run(capsys, *argv)
    assert status == 130 and "1 of 3 episodes are staged" in err
    assert Staging(DATASET_ID).staged() == {0}  # the interrupted episode was not recorded
    assert not dataset_path(DATASET_ID).exists()


def test_ctrl_c_during_a_rollout_exits_130(capsys, monkeypatch) -> None:
    monkeypatch.setattr(expert.planner, "plan", interrupted_solve)
    status, out, err = run(capsys, "rollout", "--scenario", EXAMPLE)
    assert status == 130 and out == "" and "interrupted" in err


@pytest.mark.parametrize(("family", "policy"), [("basic", "random"), ("multi", "expert")])
def test_sigint_stops_generate_at_the_episode_in_flight(minari_root: Path, family: str, policy: str) -> None:
    """A real SIGINT to a running ``generate``; with the expert it mostly lands in a SCIP solve.

    Before the fix a solve swallowed it and the run went on: here it would never end (the
    safety timeout fails it), or stage more episodes than the one in flight.
    """
    process = cli_process(
        "generate", "--family", family, "--policy", policy, "--episodes", "100000", "--dataset-id", DATASET_ID,
        minari_root=minari_root, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
    )  # fmt: skip
    staging = Staging(DATASET_ID)
    wait_for(staging.staged, "a staged episode", process)
    at_signal = len(signal_while_frozen(process, signal.SIGINT, staging.staged))
    status, _, err = finish(process)
    assert status == 130 and "Traceback" not in err and "run the same command again" in err
    assert at_signal <= len(staging.staged()) <= at_signal + 1  # one worker: at most its episode in flight


def test_an_interrupted_then_resumed_dataset_equals_an_uninterrupted_one(capsys, minari_root: Path) -> None:
    """SIGINT in the middle of expert episodes, then a resume: every episode is the one an uninterrupted run makes.

    The interrupted run asks for more episodes than it can make before the signal, so the
    signal always lands in the run; the resume and the uninterrupted run make two more.
    """
    import h5py

    argv = ["generate", "--family", "multi", "--seed", "11", "--no-progress"]
    process = cli_process(*argv, "--episodes", "100000", "--dataset-id", DATASET_ID, minari_root=minari_root,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)  # fmt: skip
    staging = Staging(DATASET_ID)
    wait_for(staging.staged, "a staged episode", process)
    signal_while_frozen(process, signal.SIGINT, staging.staged)
    status, _, err = finish(process)
    assert status == 130, err
    staged = len(staging.staged())
    assert staging.staged() == set(range(staged))  # one worker: the first episodes, in order
    episodes = staged + 2
    status, out, err = run(capsys, *argv, "--episodes", episodes, "--dataset-id", DATASET_ID)  # the resume
    assert status == 0 and f"{staged} resumed, 2 generated" in out, err
    status, _, err = run(capsys, *argv, "--episodes", episodes, "--dataset-id", "fetchcarry/whole-v0")  # in one go
    assert status == 0, err
    files = [h5py.File(dataset_path(d) / "data" / "main_data.hdf5") for d in (DATASET_ID, "fetchcarry/whole-v0")]
    try:
        for k in range(episodes):
            resumed, whole = (f[f"episode_{k}"] for f in files)
            assert np.array_equal(resumed["actions"][()], whole["actions"][()]), k
            assert np.array_equal(resumed["infos"]["objective"][()], whole["infos"]["objective"][()], equal_nan=True)
    finally:
        for file in files:
            file.close()


def test_an_internal_error_exits_3_with_the_path_of_a_full_report(capsys, monkeypatch) -> None:
    def broken(*args, **kwargs):
        raise RuntimeError("a bug")

    monkeypatch.setattr(training.cli.planning, "load_plan", broken)
    status, _, err = run(capsys, "validate", EXAMPLE, EXAMPLE)
    assert status == 3 and "internal error: RuntimeError: a bug" in err
    report = Path(err.split("the full report is in ")[1].strip())
    assert "Traceback" in report.read_text() and "a bug" in report.read_text()


def test_a_closed_pipe_ends_quietly(tmp_path: Path) -> None:
    process = cli_process("plan", EXAMPLE, "-o", tmp_path / "p.json", minari_root=tmp_path, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE)  # fmt: skip
    process.stdout.close()  # the reader (| head) went away before anything was written
    err = process.stderr.read()
    process.wait(timeout=SAFETY_TIMEOUT_S)
    assert "Traceback" not in err and "BrokenPipeError" not in err and "Exception ignored" not in err
    assert process.returncode == 141


def test_workers_die_with_their_parent(tmp_path: Path) -> None:
    """SIGKILL of ``generate --workers 2``: both workers and the resource tracker end with it."""
    psutil = pytest.importorskip("psutil")
    process = cli_process(
        "generate", "--family", "push", "--episodes", "100000", "--workers", "2", "--dataset-id", DATASET_ID,
        "--no-progress", minari_root=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    parent = psutil.Process(process.pid)

    def workers_and_tracker() -> list:
        children = parent.children(recursive=True)
        workers = [c for c in children if "resource_tracker" not in " ".join(c.cmdline())]
        return children if len(workers) >= 2 else []

    children = wait_for(workers_and_tracker, "two workers", process)
    process.kill()
    process.wait()
    wait_for(lambda: not [c for c in children if _running(c, psutil)], "the end of every child")


def _running(process, psutil) -> bool:
    """Whether ``process`` still runs: a zombie (dead, not yet reaped by its new parent) does not."""
    try:
        return process.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


# ---------------------------------------------------------------------------- 3. datasets never corrupted
def test_a_second_run_on_a_locked_dataset_id_exits_2_naming_the_holder(capsys) -> None:
    with DatasetLock(DATASET_ID):
        status, _, err = generate_random(capsys)
    assert status == 2 and "another run is working on dataset 'fetchcarry/hard-v0'" in err
    assert f"process {os.getpid()}" in err
    assert not dataset_path(DATASET_ID).exists()
    status, _, err = generate_random(capsys)  # the lock goes with its holder
    assert status == 0, err


def test_a_lock_held_by_another_process_refuses_a_run(capsys, tmp_path: Path, minari_root: Path) -> None:
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time; from training.data.staging import DatasetLock\n"
         f"with DatasetLock({DATASET_ID!r}):\n    print('held', flush=True); time.sleep({SAFETY_TIMEOUT_S})"],
        env={**os.environ, "PYTHONPATH": str(ROOT), "MINARI_DATASETS_PATH": str(minari_root)},
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert holder.stdout.readline().strip() == "held"
        status, _, err = generate_random(capsys)
        assert status == 2 and f"process {holder.pid}" in err
    finally:
        holder.kill()
        holder.wait()


def test_a_corrupt_staged_episode_is_set_aside_and_made_again(capsys) -> None:
    status, _, _ = run(capsys, "generate", "--family", "basic", "--policy", "random", "--episodes", "3",
                       "--dataset-id", DATASET_ID, "--no-progress", "--json")  # fmt: skip
    assert status == 0
    # Stage two episodes of another dataset, then spoil one, as an interrupted run with a bad disk would leave it.
    other = "fetchcarry/hard-v1"
    staging = Staging(other)

    config = GenerationConfig(other, 3, EpisodeSource(family="basic", policy="random", time_limit=DATASET_TIME_LIMIT))
    staging.start(config.manifest())
    for index in (0, 1):
        staging.write(index, run_indexed_episode(config.source, index))
    staging.episode_path(1).write_bytes(staging.episode_path(1).read_bytes()[:200])
    status, out, err = generate_random(capsys, other, 3)
    assert status == 0, err
    assert f"the staged episode {staging.episode_path(1)} could not be read" in err
    assert "1 resumed, 2 generated" in out
    assert len(list((dataset_path(other)).glob("data/*.hdf5"))) == 1


def test_a_staged_episode_that_cannot_be_read_names_its_file() -> None:
    staging = Staging(DATASET_ID)
    staging.start({})
    staging.episode_path(0).write_bytes(b"not a zip file")
    with pytest.raises(StagingError, match=r"episode_000000\.npz cannot be read"):
        staging.read(0)


def test_a_corrupt_manifest_names_the_file(capsys) -> None:
    staging = Staging(DATASET_ID)
    staging.start({})
    (staging.path / "manifest.json").write_text("{not json")
    status, _, err = generate_random(capsys)
    assert status == 2 and f"the staging manifest {staging.path / 'manifest.json'} is not valid JSON" in err
    assert "--overwrite" in err
    status, _, err = generate_random(capsys, DATASET_ID, 2, "--overwrite")
    assert status == 0, err


def test_overwrite_keeps_the_old_dataset_until_the_new_one_is_whole(capsys, monkeypatch, dataset: str) -> None:
    before = json.loads((dataset_path(dataset) / "data" / "metadata.json").read_text())

    def killed(*args, **kwargs):
        raise KeyboardInterrupt  # the run is stopped after the new dataset was written, before the swap

    with monkeypatch.context() as patch:
        patch.setattr(training.data.generate, "publish", killed)
        status, _, _ = generate_random(capsys, dataset, 3, "--overwrite")
    assert status == 130
    assert json.loads((dataset_path(dataset) / "data" / "metadata.json").read_text()) == before
    status, _, err = generate_random(capsys, dataset, 3, "--overwrite")
    assert status == 0, err
    assert json.loads((dataset_path(dataset) / "data" / "metadata.json").read_text())["total_episodes"] == 3


def test_an_interrupted_two_step_replacement_is_repaired(dataset: str) -> None:
    """Where folders cannot be exchanged atomically: a kill between the two renames loses nothing."""

    aside = Staging(dataset).path / "replaced"
    aside.parent.mkdir(parents=True)
    os.rename(dataset_path(dataset), aside)  # the first rename happened, the second did not
    recover_replaced(dataset, aside)
    assert (dataset_path(dataset) / "data" / "metadata.json").is_file() and not aside.exists()


def test_no_space_to_assemble_exits_2_and_keeps_the_staged_episodes(capsys, monkeypatch) -> None:
    usage = shutil_module.disk_usage(".")
    with monkeypatch.context() as patch:
        patch.setattr(training.data.datasets.shutil, "disk_usage", lambda path: usage._replace(free=1000))
        status, _, err = generate_random(capsys)
    assert status == 2 and "not enough free space to assemble 'fetchcarry/hard-v0'" in err
    assert Staging(DATASET_ID).staged() == {0, 1}
    status, out, _ = generate_random(capsys)
    assert status == 0 and "2 resumed" in out


def test_an_unwritable_target_is_exit_2_with_the_path(capsys, minari_root: Path) -> None:
    (minari_root / ".staging").write_text("a file where a folder must be")
    status, _, err = generate_random(capsys)
    assert status == 2 and str(minari_root / ".staging") in err


def test_a_finished_dataset_cleans_its_staging_and_a_rerun_says_complete(capsys, dataset: str) -> None:
    assert not Staging(dataset).exists()
    # a kill right after the final rename leaves the staging behind
    Staging(dataset).start({"left": "over"})
    status, out, err = generate_random(capsys)
    assert status == 0 and "is already complete (2 episodes)" in out, err
    assert not Staging(dataset).exists()
    status, _, err = generate_random(capsys, dataset, 5)  # other options: not the same dataset
    assert status == 2 and "already exists" in err and "--overwrite" in err


@pytest.mark.parametrize("dataset_id", ["badid", "fetchcarry/push", "fetchcarry/push-vX", "../escape-v0", ""])
def test_a_bad_dataset_id_is_exit_2(capsys, dataset_id: str) -> None:
    status, _, err = generate_random(capsys, dataset_id)
    assert status == 2 and "is not a Minari id" in err
    status, _, err = run(capsys, "dataset", "info", dataset_id)
    assert status == 2 and "is not a Minari id" in err


def test_a_full_disk_while_staging_is_exit_2_with_the_path(capsys, monkeypatch) -> None:
    def full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(training.data.staging.np, "savez", full)
    status, _, err = generate_random(capsys)
    assert status == 2 and "No space left on device" in err
    assert str(Staging(DATASET_ID).episode_path(0)) in err
    assert not list(Staging(DATASET_ID).path.glob(".episode_*"))  # no temporary file left behind


def test_a_plan_whose_solve_was_interrupted_is_not_written(capsys, monkeypatch, tmp_path: Path) -> None:
    """Should the planner report SCIP's status instead of raising, the command still writes nothing."""

    interrupted = Plan(scenario="s", status="userinterrupt", objective=None)
    monkeypatch.setattr(expert.planner, "plan", lambda *args, **kwargs: interrupted)
    output = tmp_path / "out.plan.json"
    status, _, err = run(capsys, "plan", EXAMPLE, "-o", output)
    assert status == 130 and "interrupted" in err and not output.exists()


def test_every_env_of_the_project_is_trusted_with_plain_arguments_only() -> None:
    phases = EnvSpec(
        "FetchCarryPushPhases-v0",
        "fetchcarry_env.phase_env:make_phase_env",
        kwargs={"family": "basic", "reward": "learning"},
    )
    assert trusted_env_spec(phases, "d/x-v0") == ("FetchCarryPushPhases-v0", {"family": "basic", "reward": "learning"})
    foreign = EnvSpec("FetchCarryPushPhases-v0", "fetchcarry_env.env:FetchCarryPushEnv")  # another id's entry point
    with pytest.raises(UnknownEnvError, match="names an unknown env"):
        trusted_env_spec(foreign, "d/x-v0")
    with pytest.raises(UnknownEnvError, match="layout"):
        trusted_env_spec(EnvSpec(phases.id, phases.entry_point, kwargs={"layout": "x"}), "d/x-v0")


def test_ctrl_c_during_evaluate_expert_keeps_what_finished(capsys, monkeypatch, tmp_path: Path) -> None:
    real = training.evaluation.expert.run_episodes

    def two_then_interrupt(*args, **kwargs):
        for count, item in enumerate(real(*args, **kwargs)):
            if count == 2:
                raise KeyboardInterrupt
            yield item

    monkeypatch.setattr(training.evaluation.expert, "run_episodes", two_then_interrupt)
    failures = tmp_path / "failures"
    status, out, err = run(
        capsys, "evaluate-expert", "--families", "basic", "--episodes", "5", "--time-limit", "0.0001",
        "--failures-dir", failures, "--no-progress",
    )  # fmt: skip
    assert status == 130 and "interrupted after 2 finished episode(s)" in err
    assert "failed: basic seed 0" in out and "failed: basic seed 1" in out
    written = sorted(p.name for p in failures.glob("*.outcome.json"))
    assert written == ["basic-seed0.outcome.json", "basic-seed1.outcome.json"]


# ---------------------------------------------------------------------------- round 2, 0. a dataset missing its spaces
def plant_command(dataset_id: str, marker: Path) -> None:
    """The bypass: the env entry point is a shell command and the action space is gone, so Minari would make the env."""
    edit_env_spec(dataset_id, entry_point="os:system", kwargs={"command": f"touch {marker}"})
    metadata_file = dataset_path(dataset_id) / "data" / "metadata.json"
    metadata = json.loads(metadata_file.read_text())
    del metadata["action_space"]
    metadata_file.write_text(json.dumps(metadata))


OPENING_COMMANDS = {
    "info": ("dataset", "info", DATASET_ID),
    "replay": ("dataset", "replay", DATASET_ID, "--episode", "0"),
    "bc": ("train", "bc", "--dataset", DATASET_ID, "--epochs", "1"),
    "dagger": ("train", "dagger", "--family", "basic", "--dataset", DATASET_ID, "--iterations", "1"),
}


@pytest.mark.parametrize("command", sorted(OPENING_COMMANDS))
def test_a_dataset_without_its_action_space_runs_no_command(capsys, tmp_path: Path, dataset: str, command: str) -> None:
    marker = tmp_path / "MARKER"
    plant_command(dataset, marker)
    argv = OPENING_COMMANDS[command] + (("--out", tmp_path / "run") if command in ("bc", "dagger") else ())
    status, out, err = run(capsys, *argv)
    assert not marker.exists(), "the dataset ran its command"
    assert status == 2 and out == "", err
    assert str(dataset_path(dataset) / "data" / "metadata.json") in err


@pytest.mark.parametrize(
    "edit",
    [
        lambda m: m.pop("total_episodes"),
        lambda m: m.pop("observation_space"),
        lambda m: m.update(total_episodes=5),  # more episodes than the HDF5 file holds
        lambda m: m.update(total_episodes="2"),
        lambda m: m.update(env_spec=7),
        lambda m: m.update(env_spec="{not json"),
        lambda m: m.update(observation_space='{"type": "Box"}'),
        lambda m: m.update(author=5),
        lambda m: m.update(dataset_size="big"),
        lambda m: m.update(data_format="arrow"),
        lambda m: m.update(minari_version=None),
        lambda m: m.clear(),
    ],
    ids=["no-episodes", "no-observation-space", "more-episodes", "episodes-text", "spec-number", "spec-not-json",
         "space-no-shape", "author-number", "size-text", "arrow", "no-version", "empty"],
)  # fmt: skip
def test_a_hand_edited_metadata_file_is_exit_2_naming_it(capsys, dataset: str, edit) -> None:
    metadata_file = dataset_path(dataset) / "data" / "metadata.json"
    metadata = json.loads(metadata_file.read_text())
    edit(metadata)
    metadata_file.write_text(json.dumps(metadata))
    for argv in (OPENING_COMMANDS["info"], OPENING_COMMANDS["replay"]):
        status, out, err = run(capsys, *argv)
        assert status == 2 and out == "", err
        assert str(metadata_file) in err


# ---------------------------------------------------------------------------- round 2, 4. every input file, every flag
class Hung(Exception):
    """A command that waited too long (a FIFO opened for reading waits for a writer forever)."""


@pytest.fixture
def no_hang():
    """Fail a test whose command still blocks after the safety timeout (a hang), instead of hanging the suite."""

    def hung(signum, frame):
        raise Hung

    previous = signal.signal(signal.SIGALRM, hung)
    signal.alarm(SAFETY_TIMEOUT_S)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, previous)


def fifo_commands(fifo: Path, tmp_path: Path) -> dict[str, tuple]:
    folder = tmp_path / "scenarios"
    folder.mkdir()
    os.mkfifo(folder / "a.json")
    return {
        "plan": ("plan", fifo, "-o", tmp_path / "out.plan.json"),
        "validate-scenario": ("validate", fifo, ROOT / "tests" / "fuzz" / "push_basic.plan.json"),
        "validate-plan": ("validate", EXAMPLE, fifo),
        "rollout": ("rollout", "--scenario", fifo, "--policy", "random"),
        "benchmark": ("benchmark", "--policies", "random", "--scenarios", folder, "--out", tmp_path / "b",
                      "--no-progress"),
    }  # fmt: skip


@pytest.mark.parametrize("command", ["plan", "validate-scenario", "validate-plan", "rollout", "benchmark"])
def test_a_fifo_as_an_input_file_is_exit_2_not_a_hang(capsys, tmp_path: Path, no_hang, command: str) -> None:
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    status, _, err = run(capsys, *fifo_commands(fifo, tmp_path)[command])
    assert status == 2, err
    assert "not a regular file (a FIFO)" in err


def test_a_fifo_as_the_results_file_of_a_resumed_benchmark_is_exit_2(capsys, tmp_path: Path, no_hang) -> None:
    out = tmp_path / "b"
    out.mkdir()
    os.mkfifo(out / "results.json")
    status, _, err = run(capsys, "benchmark", "--policies", "random", "--split", "iid", "--episodes", "1",
                         "--out", out, "--resume", "--no-progress")  # fmt: skip
    assert status == 2 and "results.json: not a regular file (a FIFO)" in err, err


def test_a_fifo_as_the_config_of_a_benchmarked_run_folder_is_exit_2(capsys, tmp_path: Path, no_hang) -> None:
    run_folder = tmp_path / "run"
    run_folder.mkdir()
    os.mkfifo(run_folder / "config.json")
    status, _, err = run(capsys, "benchmark", "--policies", run_folder, "--split", "iid", "--episodes", "1",
                         "--out", tmp_path / "b", "--no-progress")  # fmt: skip
    assert status == 2 and "not a regular file (a FIFO)" in err, err


def test_many_unusable_scenario_files_are_summarised(capsys, tmp_path: Path) -> None:
    folder = tmp_path / "scenarios"
    folder.mkdir()
    for index in range(300):
        (folder / f"s{index:03d}.json").write_text("{")
    status, _, err = run(capsys, "benchmark", "--policies", "random", "--scenarios", folder, "--out", tmp_path / "b")
    assert status == 2, err
    assert "300 unusable scenario files" in err and "... and 295 more unusable files of 300" in err
    assert len(err.splitlines()) < 20, err


def test_an_unreadable_file_under_proc_is_named(capsys) -> None:
    status, _, err = run(capsys, "validate", EXAMPLE, "/proc/self/mem")
    assert status == 2 and "Input/output error: /proc/self/mem" in err, err


SEED_COMMANDS = {
    "rollout": ("rollout", "--family", "basic", "--policy", "random"),
    "demo": ("demo",),
    "generate": ("generate", "--family", "basic", "--policy", "random", "--episodes", "1", "--dataset-id", DATASET_ID),
    "evaluate-expert": ("evaluate-expert", "--families", "basic", "--episodes", "1"),
}


@pytest.mark.parametrize("value", ["-1", str(2**32), str(2**64), "1.5"])
@pytest.mark.parametrize("command", sorted(SEED_COMMANDS))
def test_a_seed_outside_0_to_2_32_is_exit_2(capsys, tmp_path: Path, command: str, value: str) -> None:
    extra = ("--out", tmp_path / "d.png") if command == "demo" else ()
    status, _, err = run(capsys, *SEED_COMMANDS[command], *extra, "--seed", value)
    assert status == 2 and "argument --seed" in err, err
    assert "internal error" not in err


BENCH_AND_TRAIN_SEEDS = {
    "benchmarks env": (bench, "env", "--episodes", "1"),
    "benchmarks generate": (bench, "generate", "--episodes", "1"),
    "benchmarks learning-checks ppo": (bench, "learning-checks", "ppo"),
    "benchmarks planner": (bench, "planner"),
    "train bc": (run, "train", "bc", "--dataset", DATASET_ID, "--out", "unused"),
    "train ppo": (run, "train", "ppo", "--family", "basic", "--out", "unused"),
}


@pytest.mark.parametrize("value", ["-1", str(2**64)])
@pytest.mark.parametrize("command", sorted(BENCH_AND_TRAIN_SEEDS))
def test_benchmarks_and_train_refuse_a_seed_outside_0_to_2_32(capsys, command: str, value: str) -> None:
    runner, *argv = BENCH_AND_TRAIN_SEEDS[command]
    status, _, err = runner(capsys, *argv, "--seed", value)
    assert status == 2 and "2**32 - 1" in err, err
    assert "internal error" not in err


@pytest.mark.parametrize("command", ["generate", "evaluate-expert"])
def test_seeds_beyond_2_32_for_later_episodes_are_exit_2(capsys, command: str) -> None:
    argv = [a if a != "1" else "2" for a in SEED_COMMANDS[command]]  # two episodes: seeds N and N + 1
    status, _, err = run(capsys, *argv, "--seed", str(2**32 - 1))
    assert status == 2 and "beyond 2**32 - 1" in err, err


def test_the_largest_seed_is_taken(capsys) -> None:
    status, out, err = run(capsys, *SEED_COMMANDS["rollout"], "--seed", str(2**32 - 1))
    assert status in (0, 1) and f"seed {2**32 - 1}" in out, err


@pytest.mark.parametrize("root", ["relative", "tilde"])
def test_a_relative_or_tilde_datasets_path_is_resolved_once(capsys, monkeypatch, tmp_path: Path, root: str) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv("MINARI_DATASETS_PATH", "rel/datasets" if root == "relative" else "~/datasets")
    expected = tmp_path / "rel" / "datasets" if root == "relative" else tmp_path / "home" / "datasets"
    status, out, err = generate_random(capsys)
    assert status == 0, err
    assert f"written to {expected / DATASET_ID}" in out
    status, out, err = run(capsys, "dataset", "info", DATASET_ID)
    assert status == 0 and str(expected / DATASET_ID) in out, err


def test_an_empty_datasets_path_is_exit_2(capsys, monkeypatch) -> None:
    monkeypatch.setenv("MINARI_DATASETS_PATH", "")
    status, _, err = generate_random(capsys)
    assert status == 2 and "MINARI_DATASETS_PATH is set but empty" in err


H5PY_DISK_FULL = (
    "Can't synchronously write data (file write failed: time = Tue Dec  1 10:00:00 2026, filename = "
    "'main_data.hdf5', file descriptor = 7, errno = 28, error message = 'No space left on device', buf = "
    "0x55d0, total write size = 8192, bytes this sub-write = 8192, bytes actually written = "
    "18446744073709551615, offset = 0)"
)


def test_a_disk_that_fills_during_the_hdf5_write_is_exit_2_and_keeps_the_episodes(capsys, monkeypatch) -> None:
    from minari.dataset._storages.hdf5_storage import HDF5Storage

    def full(*args, **kwargs):
        raise RuntimeError(H5PY_DISK_FULL)

    usage = shutil_module.disk_usage(".")
    with monkeypatch.context() as patch:
        patch.setattr(training.data.datasets.shutil, "disk_usage", lambda path: usage._replace(free=10**12))
        patch.setattr(HDF5Storage, "update_episodes", full)
        status, _, err = generate_random(capsys)
    assert status == 2 and "No space left on device" in err, err
    assert str(Staging(DATASET_ID).path / "assembling") in err
    assert Staging(DATASET_ID).staged() == {0, 1} and not (Staging(DATASET_ID).path / "assembling").exists()
    assert not dataset_path(DATASET_ID).exists()
    status, out, err = generate_random(capsys)
    assert status == 0 and "2 resumed" in out, err


def test_the_space_estimate_counts_hdf5s_cost_per_episode(capsys, monkeypatch) -> None:
    """2.7 MB free once passed the estimate for a dataset HDF5 then could not hold."""
    usage = shutil_module.disk_usage(".")
    with monkeypatch.context() as patch:
        patch.setattr(training.data.datasets.shutil, "disk_usage", lambda path: usage._replace(free=2_700_000))
        status, _, err = generate_random(capsys, DATASET_ID, 20)
    assert status == 2 and "not enough free space" in err, err
    assert Staging(DATASET_ID).staged() == set(range(20))


@pytest.mark.parametrize("blocked", ["file-in-place", "temp-under-a-file"])
def test_an_internal_error_is_exit_3_when_no_report_can_be_written(capsys, monkeypatch, tmp_path: Path, blocked):
    def broken(*args, **kwargs):
        raise RuntimeError("a bug")

    if blocked == "file-in-place":
        (tmp_path / training.cli.exits.REPORT_FOLDER).write_text("a file where the report folder goes")
        temp = tmp_path
    else:  # an unusable TMPDIR (root writes through permissions: a file in its path stops everyone)
        (tmp_path / "afile").write_text("")
        temp = tmp_path / "afile" / "tmp"
    monkeypatch.setattr(training.cli.exits.tempfile, "gettempdir", lambda: str(temp))
    monkeypatch.setattr(training.cli.planning, "load_plan", broken)
    status, _, err = run(capsys, "validate", EXAMPLE, EXAMPLE)
    assert status == 3 and "internal error: RuntimeError: a bug" in err
    assert "no full report could be written" in err and err.count("\n") == 2


BROKEN_TIMINGS = ["[]", '{"stages": []}', '{"runs": 5}', '{"runs": {"a": {"wall": "x"}}}', "{not json", "\x00"]


@pytest.mark.parametrize("content", BROKEN_TIMINGS)
def test_a_broken_timings_file_of_reproduce_is_exit_2_naming_it(capsys, tmp_path: Path, content: str) -> None:
    from dataclasses import asdict

    from training.reproduce.budgets import SMOKE

    out = tmp_path / "repro"
    out.mkdir()
    (out / "reproduce.json").write_text(json.dumps({"budget": asdict(SMOKE), "seeds": 1}))
    (out / "timings.json").write_text(content)
    status, _, err = run(capsys, "reproduce", "--out", out, "--budget", "smoke", "--seeds", "1", "--no-progress")
    assert status == 2 and str(out / "timings.json") in err, err


def test_ctrl_c_before_the_first_benchmark_episode_says_nothing_finished(capsys, monkeypatch, tmp_path: Path) -> None:
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(training.cli.benchmark, "run_benchmark", interrupted)
    out = tmp_path / "bench"
    status, _, err = run(capsys, "benchmark", "--policies", "random", "--split", "iid", "--out", out, "--no-progress")
    assert status == 130 and "before any episode finished: nothing was written" in err, err
    assert "the finished episodes are in" not in err
