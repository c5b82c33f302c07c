"""The staging folder of a dataset being generated: one file per finished episode.

Generation writes every finished episode at once to
``$MINARI_DATASETS_PATH/.staging/<dataset-id>/episode_<k>.npz`` (written to a temporary
name, then renamed, so a file is either whole or absent), next to a ``manifest.json``
that records the options the episodes were made with. An interrupted run therefore
loses no finished episode: running the same command again finds the staged episodes,
makes only the missing ones, and assembles the Minari dataset when all are there.
Minari ignores hidden folders, so the staging never shows up as a dataset.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from training.rollout import EpisodeFigures, EpisodeRecord

STAGING_FOLDER = ".staging"
MANIFEST = "manifest.json"
_EPISODE_FILE = re.compile(r"^episode_(\d{6,})\.npz$")


def datasets_root() -> Path:
    """Where Minari keeps local datasets (``MINARI_DATASETS_PATH`` or ``~/.minari/datasets``)."""
    from minari.storage.datasets_root_dir import get_dataset_path

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
        return json.loads(file.read_text()) if file.is_file() else None

    def start(self, manifest: dict[str, Any]) -> None:
        """Create the folder and record ``manifest`` (the generation options)."""
        self.path.mkdir(parents=True, exist_ok=True)
        _atomic_write(self.path / MANIFEST, (json.dumps(manifest, indent=2, sort_keys=True) + "\n").encode())

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
        handle, temporary = tempfile.mkstemp(dir=self.path, prefix=".episode_", suffix=".tmp")
        try:
            with os.fdopen(handle, "wb") as file:
                np.savez(file, **arrays)
                file.flush()
                os.fsync(file.fileno())
            os.replace(temporary, self.episode_path(index))
        except BaseException:
            Path(temporary).unlink(missing_ok=True)
            raise

    def read(self, index: int) -> EpisodeRecord:
        """Episode ``index`` as it was staged (without frames)."""
        with np.load(self.episode_path(index), allow_pickle=False) as data:
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


def _atomic_write(path: Path, data: bytes) -> None:
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    with os.fdopen(handle, "wb") as file:
        file.write(data)
    os.replace(temporary, path)
