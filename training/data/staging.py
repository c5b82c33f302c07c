"""The staging folder of a dataset being generated: one file per finished episode.

Generation writes every finished episode at once to
``$MINARI_DATASETS_PATH/.staging/<dataset-id>/episode_<k>.npz`` (written to a temporary
name, then renamed, so a file is either whole or absent), next to a ``manifest.json``
that records the options the episodes were made with. An interrupted run therefore
loses no finished episode: running the same command again finds the staged episodes,
makes only the missing ones, and assembles the Minari dataset when all are there.
Minari ignores hidden folders, so the staging never shows up as a dataset.

Every file error names the file: a manifest that is not JSON raises
:class:`StagingError`; a staged episode that cannot be read is found by
:meth:`Staging.set_aside_corrupt` (a resume calls it), moved to ``corrupt/`` and made
again. :class:`DatasetLock` keeps two runs from working on one dataset id at once.
"""

from __future__ import annotations

import datetime
import fcntl
import json
import os
import re
import shutil
import sys
import zipfile
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from fetchcarry_env.errors import InputError
from training.files import atomic_file, write_atomically
from training.rollout import EpisodeFigures, EpisodeRecord

DATASETS_ENV = "MINARI_DATASETS_PATH"  # Minari's variable: where local datasets live
STAGING_FOLDER = ".staging"
MANIFEST = "manifest.json"
CORRUPT_FOLDER = "corrupt"  # staged episodes that could not be read, kept for a post-mortem
LOCK_SUFFIX = ".lock"
_EPISODE_FILE = re.compile(r"^episode_(\d{6,})\.npz$")


def datasets_root() -> Path:
    """Where Minari keeps local datasets (``MINARI_DATASETS_PATH`` or ``~/.minari/datasets``), an absolute path.

    A relative ``MINARI_DATASETS_PATH`` (or one starting with ``~``) is resolved against
    the current folder (the home folder) the first time, and written back to the
    environment, so that Minari's own calls, later calls and worker processes all use
    the same folder. An empty one is bad input.
    """
    from minari.storage.datasets_root_dir import get_dataset_path  # minari (h5py) only when a dataset is used

    raw = os.environ.get(DATASETS_ENV)
    if raw is not None:
        if not raw.strip():
            raise InputError(f"{DATASETS_ENV} is set but empty: give it a folder, or unset it for ~/.minari/datasets")
        absolute = os.path.abspath(os.path.expanduser(raw))
        if absolute != raw:
            os.environ[DATASETS_ENV] = absolute
    return Path(get_dataset_path())


class Staging:
    """The staging folder of one dataset id."""

    def __init__(self, dataset_id: str, root: Path | None = None) -> None:
        self.dataset_id = dataset_id
        self.path = (root or datasets_root()) / STAGING_FOLDER / dataset_id

    def exists(self) -> bool:
        return self.path.is_dir()

    def manifest(self) -> dict[str, Any] | None:
        """The options the staged episodes were made with, or ``None`` if nothing is staged."""
        file = self.path / MANIFEST
        if not file.is_file():
            return None
        try:
            manifest = json.loads(file.read_text())
        except (UnicodeDecodeError, json.JSONDecodeError) as error:
            raise StagingError(f"the staging manifest {file} is not valid JSON ({error})") from None
        if not isinstance(manifest, dict):
            raise StagingError(f"the staging manifest {file} is not a JSON object")
        return manifest

    def start(self, manifest: dict[str, Any]) -> None:
        """Create the folder and record ``manifest`` (the generation options)."""
        self.path.mkdir(parents=True, exist_ok=True)
        write_atomically(self.path / MANIFEST, (json.dumps(manifest, indent=2, sort_keys=True) + "\n").encode())

    def staged(self) -> set[int]:
        """Indices of the episodes already staged."""
        if not self.exists():
            return set()
        return {int(m.group(1)) for f in self.path.iterdir() if (m := _EPISODE_FILE.match(f.name))}

    def episode_path(self, index: int) -> Path:
        return self.path / f"episode_{index:06d}.npz"

    def write(self, index: int, record: EpisodeRecord) -> None:
        """Stage episode ``index`` atomically (temporary file, then rename)."""
        arrays: dict[str, np.ndarray] = {
            "actions": record.actions,
            "rewards": record.rewards,
            "terminations": record.terminations,
            "truncations": record.truncations,
            "meta": np.array(
                json.dumps({"seed": record.seed, "scenario": record.scenario, "figures": record.figures.to_dict()})
            ),
        }
        arrays.update({f"observations/{k}": v for k, v in record.observations.items()})
        arrays.update({f"infos/{k}": v for k, v in record.infos.items()})
        with atomic_file(self.episode_path(index), durable=True) as file:
            np.savez(file, **arrays)

    def read(self, index: int) -> EpisodeRecord:
        """Episode ``index`` as it was staged (without frames); a file that cannot be read is a ``StagingError``."""
        path = self.episode_path(index)
        try:
            return self._read(path)
        except (OSError, EOFError, ValueError, KeyError, TypeError, zipfile.BadZipFile) as error:
            raise StagingError(f"the staged episode {path} cannot be read ({type(error).__name__}: {error})") from None

    def check(self, index: int) -> None:
        """Raise ``StagingError`` unless episode ``index``'s file is whole (every CRC) and readable."""
        path = self.episode_path(index)
        try:
            with zipfile.ZipFile(path) as archive:
                broken = archive.testzip()
            if broken is not None:
                raise zipfile.BadZipFile(f"bad CRC in {broken}")
        except (OSError, EOFError, zipfile.BadZipFile) as error:
            raise StagingError(f"the staged episode {path} cannot be read ({type(error).__name__}: {error})") from None
        self.read(index)

    def set_aside_corrupt(self) -> list[tuple[Path, Path]]:
        """Move every staged episode that cannot be read to ``corrupt/``; return (file, where it went) pairs."""
        moved = []
        for index in sorted(self.staged()):
            try:
                self.check(index)
            except StagingError:
                source = self.episode_path(index)
                folder = self.path / CORRUPT_FOLDER
                folder.mkdir(exist_ok=True)
                stamp = datetime.datetime.now(datetime.UTC).strftime("%Y%m%dT%H%M%S%fZ")
                target = folder / f"{source.name}.{stamp}"
                os.replace(source, target)
                moved.append((source, target))
        return moved

    def size_bytes(self) -> int:
        """Bytes of the staged episode files."""
        return sum(self.episode_path(k).stat().st_size for k in self.staged())

    @staticmethod
    def _read(path: Path) -> EpisodeRecord:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            observations = {k.split("/", 1)[1]: data[k] for k in data.files if k.startswith("observations/")}
            infos = {k.split("/", 1)[1]: data[k] for k in data.files if k.startswith("infos/")}
            return EpisodeRecord(
                seed=meta["seed"],
                scenario=meta["scenario"],
                observations=observations,
                actions=data["actions"],
                rewards=data["rewards"],
                terminations=data["terminations"],
                truncations=data["truncations"],
                infos=infos,
                figures=EpisodeFigures(**meta["figures"]),
            )

    def remove(self) -> None:
        """Delete the staging folder and everything in it."""
        if self.exists():
            shutil.rmtree(self.path)


class StagingError(InputError):
    """A staging file (the manifest, a staged episode) cannot be read; the message names it."""


class DatasetBusyError(InputError):
    """Another run holds the lock of a dataset id."""


class DatasetLock:
    """An exclusive lock on one dataset id (``flock`` on ``.staging/<id>.lock``), held while a run works on it.

    The operating system releases it when the holder exits, however it exits (even
    ``SIGKILL``), so a stale lock never blocks a later run. The file records the holder's
    process id, start time and command line, which the refusal quotes.
    """

    def __init__(self, dataset_id: str, root: Path | None = None) -> None:
        self.dataset_id = dataset_id
        self.path = (root or datasets_root()) / STAGING_FOLDER / f"{dataset_id}{LOCK_SUFFIX}"
        self._file: Any = None

    def __enter__(self) -> DatasetLock:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        file = open(self.path, "a+")  # held open for as long as the lock is
        try:
            fcntl.flock(file.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            file.seek(0)
            holder = file.read().strip() or "unknown"
            file.close()
            raise DatasetBusyError(
                f"another run is working on dataset {self.dataset_id!r} ({holder}); wait for it to finish "
                f"(lock file {self.path})"
            ) from None
        file.seek(0)
        file.truncate()
        started = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
        file.write(f"process {os.getpid()}, started {started}: {' '.join(sys.argv)}\n")
        file.flush()
        self._file = file
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, traceback: TracebackType | None
    ) -> None:
        if self._file is not None:
            self._file.close()  # closing releases the flock
            self._file = None
