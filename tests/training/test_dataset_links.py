"""A dataset's HDF5 file that would make a reader read elsewhere, or more than it holds, is refused (exit 2).

Red-team item 1 of "The first hour": links in ``main_data.hdf5`` (an external link into a
FIFO hung every reader; a soft link to itself was exit 3), external raw storage (training
ran on ``/dev/zero`` or another file's bytes), a virtual dataset, and a declared shape far
beyond the episode's steps (exit 3, ``MemoryError``). ``metadata.json`` is left as it was
in every case. Each hostile file is made from a small phases dataset of the project's own
generator, copied for each test.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np
import pytest
from cli_run import run

import training.data.hdf5_checks
from training.cli import main

DATASET_ID = "fetchcarry/links-v0"
ROOT = Path(__file__).resolve().parents[2]
SAFETY_TIMEOUT_S = 300  # seconds: stops a command that hangs; not a bound on how long one takes
OBSERVATION = "episode_0/observations/observation"

COMMANDS = {
    "info": ("dataset", "info", DATASET_ID),
    "replay": ("dataset", "replay", DATASET_ID, "--episode", "1"),
    "render": ("dataset", "render", DATASET_ID, "--obs-mode", "topdown", "--out", "fetchcarry/rendered-v0",
               "--no-progress"),
    "train bc": ("train", "bc", "--dataset", DATASET_ID, "--epochs", "1", "--no-progress"),
    "train dagger": ("train", "dagger", "--family", "basic", "--dataset", DATASET_ID, "--demonstrations", "1",
                     "--iterations", "1", "--no-progress"),
}  # fmt: skip


@pytest.fixture(scope="module")
def generated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A Minari folder holding a two-episode phases dataset (made once for the module)."""
    root = tmp_path_factory.mktemp("minari")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(root))
        status = main(["generate", "--family", "basic", "--episodes", "2", "--interface", "phases", "--dataset-id",
                       DATASET_ID, "--no-progress"])  # fmt: skip
    assert status == 0
    return root


@pytest.fixture
def main_data(generated: Path, minari_root: Path) -> Path:
    """This test's copy of the dataset (in its own MINARI_DATASETS_PATH): the path of its HDF5 file."""
    shutil.rmtree(minari_root)
    shutil.copytree(generated, minari_root)
    return minari_root / DATASET_ID / "data" / "main_data.hdf5"


def edit(main_data: Path, change: Callable[[h5py.File], None]) -> None:
    with h5py.File(main_data, "a") as file:
        change(file)


def command(name: str, tmp_path: Path) -> tuple[str, ...]:
    """The command line of ``name``, with a new run folder for a training command."""
    return COMMANDS[name] + (("--out", str(tmp_path / "run")) if name.startswith("train") else ())


def assert_refused(status: int, out: str, err: str, main_data: Path, words: str) -> None:
    assert status == 2 and out == "", err
    assert DATASET_ID in err and str(main_data) in err and words in err, err
    assert "internal error" not in err


def replace_observation(file: h5py.File, **options) -> None:
    """Episode 0's observation vectors replaced by a dataset made with ``options`` (its shape and type kept)."""
    group = file["episode_0/observations"]
    shape, dtype = group["observation"].shape, group["observation"].dtype
    del group["observation"]
    group.create_dataset("observation", **{"shape": shape, "dtype": dtype, **options})


# ---------------------------------------------------------------------------- links
@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_an_external_link_into_a_fifo_is_refused_without_hanging(main_data: Path, tmp_path: Path, name: str) -> None:
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)

    def link_episode(file: h5py.File) -> None:
        del file["episode_0"]
        file["episode_0"] = h5py.ExternalLink(str(fifo), "/episode_0")

    edit(main_data, link_episode)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MINARI_DATASETS_PATH": str(main_data.parents[3])}
    try:
        done = subprocess.run([sys.executable, "-m", "training.cli", *command(name, tmp_path)], env=env, cwd=ROOT,
                              capture_output=True, text=True, timeout=SAFETY_TIMEOUT_S)  # fmt: skip
    except subprocess.TimeoutExpired:
        pytest.fail(f"fetchcarry {name} still ran after the safety timeout of {SAFETY_TIMEOUT_S} s: a hang")
    assert_refused(done.returncode, done.stdout, done.stderr, main_data, "episode_0 is an external link")
    assert str(fifo) in done.stderr


@pytest.mark.parametrize("name", ["info", "train bc"])
def test_a_soft_link_to_itself_is_refused(capsys, main_data: Path, tmp_path: Path, name: str) -> None:
    def loop(file: h5py.File) -> None:
        del file["episode_0"]
        file["episode_0"] = h5py.SoftLink("/episode_0")

    edit(main_data, loop)
    assert_refused(*run(capsys, *command(name, tmp_path)), main_data, "episode_0 is a soft link")


def test_a_soft_link_inside_an_episode_is_refused(capsys, main_data: Path) -> None:
    def link(file: h5py.File) -> None:
        del file[OBSERVATION]
        file[OBSERVATION] = h5py.SoftLink("/episode_1/observations/observation")

    edit(main_data, link)
    assert_refused(*run(capsys, *COMMANDS["info"]), main_data, f"{OBSERVATION} is a soft link")


def test_a_hard_link_back_to_an_episode_is_refused(capsys, main_data: Path) -> None:
    edit(main_data, lambda file: file["episode_0/infos"].__setitem__("loop", file["episode_0"]))
    assert_refused(*run(capsys, *COMMANDS["info"]), main_data, "has 2 names (hard links)")


# ---------------------------------------------------------------------------- storage
@pytest.mark.parametrize("name", ["info", "train bc"])
def test_external_storage_on_another_file_is_refused(capsys, main_data: Path, tmp_path: Path, name: str) -> None:
    other = tmp_path / "other.bin"
    other.write_bytes(np.arange(4 * 219, dtype=np.float32).tobytes())
    edit(main_data, lambda file: replace_observation(file, external=[(str(other), 0, h5py.h5f.UNLIMITED)]))
    status, out, err = run(capsys, *command(name, tmp_path))
    assert_refused(status, out, err, main_data, f"{OBSERVATION} keeps its data in another file (external storage")
    assert str(other) in err


@pytest.mark.parametrize("name", ["info", "train bc"])
def test_external_storage_on_dev_zero_is_refused(capsys, main_data: Path, tmp_path: Path, name: str) -> None:
    edit(main_data, lambda file: replace_observation(file, external=[("/dev/zero", 0, h5py.h5f.UNLIMITED)]))
    assert_refused(*run(capsys, *command(name, tmp_path)), main_data, "(external storage: '/dev/zero')")


def test_a_virtual_dataset_is_refused(capsys, main_data: Path, tmp_path: Path) -> None:
    source = tmp_path / "source.hdf5"
    with h5py.File(source, "w") as file:
        file["x"] = np.zeros((4, 219), np.float32)

    def virtual(file: h5py.File) -> None:
        layout = h5py.VirtualLayout(shape=(4, 219), dtype=np.float32)
        layout[:] = h5py.VirtualSource(str(source), "x", shape=(4, 219))
        del file[OBSERVATION]
        file["episode_0/observations"].create_virtual_dataset("observation", layout)

    edit(main_data, virtual)
    assert_refused(*run(capsys, *command("train bc", tmp_path)), main_data, f"{OBSERVATION} is a virtual dataset")


def test_a_compressed_dataset_is_refused(capsys, main_data: Path) -> None:
    edit(main_data, lambda file: replace_observation(file, compression="gzip", data=np.zeros((4, 219), np.float32)))
    assert_refused(*run(capsys, *COMMANDS["info"]), main_data, f"{OBSERVATION} is compressed or filtered")


# ---------------------------------------------------------------------------- declared shapes
@pytest.mark.parametrize("name", ["info", "train bc"])
def test_a_shape_far_beyond_the_episodes_steps_is_refused(capsys, main_data: Path, tmp_path: Path, name: str) -> None:
    edit(main_data, lambda file: replace_observation(file, shape=(10**9, 219), chunks=(4, 219)))
    status, out, err = run(capsys, *command(name, tmp_path))
    assert_refused(status, out, err, main_data, f"{OBSERVATION}: shape (1000000000, 219)")
    assert "MemoryError" not in err


def test_rows_far_wider_than_stored_are_refused(capsys, main_data: Path) -> None:
    def wide_info(file: h5py.File) -> None:
        file["episode_0/infos"].create_dataset("wide", shape=(4, 10**9), dtype=np.float64, chunks=(1, 1024))

    edit(main_data, wide_info)
    assert_refused(*run(capsys, *COMMANDS["info"]), main_data, "bytes, more than the file's")


def test_an_episodes_steps_that_disagree_with_the_metadata_are_refused(capsys, main_data: Path) -> None:
    edit(main_data, lambda file: file["episode_1"].attrs.__setitem__("total_steps", 10**9))
    assert_refused(*run(capsys, *COMMANDS["info"]), main_data, "episode_1: total_steps 1,000,000,000")


def test_an_observation_outside_the_recorded_space_is_refused(capsys, main_data: Path) -> None:
    edit(main_data, lambda file: file["episode_0/observations"].create_dataset("extra", data=np.zeros((4, 3))))
    assert_refused(*run(capsys, *COMMANDS["info"]), main_data, "episode_0/observations/extra is a dataset: no part")


# ---------------------------------------------------------------------------- a bounded walk
def test_an_episode_of_many_groups_is_refused(capsys, main_data: Path) -> None:
    def many(file: h5py.File) -> None:
        for k in range(training.data.hdf5_checks.MAX_LINKS_PER_EPISODE):
            file["episode_0/infos"].create_group(f"g{k}")

    edit(main_data, many)
    assert_refused(*run(capsys, *COMMANDS["info"]), main_data, "episode_0 holds more than 64 groups and datasets")


def test_a_file_beyond_the_cap_of_links_is_refused(capsys, monkeypatch, main_data: Path) -> None:
    monkeypatch.setattr(training.data.hdf5_checks, "MAX_HDF5_LINKS", 30)  # the two episodes hold 42
    assert_refused(*run(capsys, *COMMANDS["info"]), main_data, "more than the 30 links")


# ---------------------------------------------------------------------------- the untouched dataset
def test_the_untouched_dataset_still_loads_replays_and_trains(capsys, main_data: Path, tmp_path: Path) -> None:
    for name in ("info", "replay", "train bc"):
        status, _, err = run(capsys, *command(name, tmp_path))
        assert status == 0, (name, err)
    assert (tmp_path / "run" / "model.pt").exists()
