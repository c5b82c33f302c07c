"""Minari datasets of fetchcarry episodes: assembly from the staging, summary, exact replay.

A dataset is an ordinary Minari 0.5 dataset (``minari.load_dataset(id)`` reads it). Its
env is rebuilt by :func:`make_recorded_env`, never by Minari's ``recover_environment()``:
that one ``gym.make``s whatever entry point the dataset's ``metadata.json`` names, so an
edited file would run any code. :func:`trusted_env_spec` accepts only this project's env
ids with their registered entry points and plain keyword arguments. Besides the
observations, actions, rewards and flags, each episode stores:

- its ``seed`` (Minari's episode seed) and its ``scenario`` (the ``fetchcarry-scenario/1``
  JSON) in the episode metadata, so it replays exactly, as ManiSkill stores its reset
  arguments; and the episode's figures (``outcome``, ``success``, ``delivered``,
  ``plans``, ``replans``, ``planner_failures``, ``objective``, ...);
- per-step infos (:data:`training.rollout.INFO_KEYS` but the planner's seconds): whether
  the policy planned or replanned before the step, whether the action was the fallback,
  refused, or stopped at a contact, and how many objects are delivered.

No wall-clock time is stored (the seconds of planning, simulation and the policy are in
the generation's report instead): the same command writes the same dataset, byte for
byte, at any load and with any number of workers.
  A ``phases`` dataset adds each state's candidate mask (``action_mask``), whether each
  step is an expert move projected onto its nearest candidate (``projected``), and the
  episode's count of those in its metadata (``projected``).

Read the episode metadata with ``dataset.storage.get_episode_metadata([k])``.

The dataset is built in the staging folder and moved into place with one rename, so
a dataset id either does not exist or holds a whole dataset.

Minari (and h5py under it) is imported by the functions that read or write a dataset,
not with this module: the command line imports it and starts without them.
"""

from __future__ import annotations

import codecs
import ctypes
import errno
import json
import math
import os
import shutil
import sys
from collections import Counter
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.envs.registration import EnvSpec

import fetchcarry_env  # noqa: F401  (registers this project's env ids: recovering and rebuilding a dataset's env)
from fetchcarry_env.errors import InputError
from fetchcarry_env.jsontext import JsonInputError, describe, parse_json, read_json
from fetchcarry_env.observation import Capacity
from fetchcarry_env.observations import modes
from fetchcarry_env.registration import do_nothing_return
from training.data.sources import GenerationConfig
from training.data.staging import Staging, datasets_root
from training.envs import make_env
from training.policies.phase_expert import PROJECTED_INFO
from training.rollout import EpisodeRecord, is_timing

AUTHOR = "fetchcarry"
CODE_URL = "https://github.com/fetchcarry/fetchcarry"
ALGORITHMS = {"expert": "fetchcarry MILP expert (SCIP), ExpertPolicy", "random": "RandomMaskedPolicy"}
ASSEMBLY_FOLDER = "assembling"  # in the staging folder: the dataset being written
REPLACED_FOLDER = "replaced"  # in the staging folder: an old dataset between the two renames of a replacement
# The assembled dataset's size, estimated from the staged files: HDF5 holds the same arrays (1.2 times the staged
# bytes measured) plus a fixed cost per episode (a group, a dataset per info key and their attributes: up to about
# 85 kB measured for a phases episode), so short expert episodes take up to 3.5 times their staged bytes.
SPACE_MARGIN = 1.5  # assembled arrays / staged files' size
EPISODE_OVERHEAD_BYTES = 128_000  # HDF5's own bytes per episode
MIN_FREE_BYTES = 16_000_000  # bytes kept free besides the estimate (the file's metadata, other writers)
_DISK_FULL = ("No space left on device", "errno = 28")  # how h5py's RuntimeError of a failed write says ENOSPC
_AT_FDCWD = -100  # Linux: paths relative to the current directory
_RENAME_EXCHANGE = 2  # Linux renameat2 flag: swap the two paths
REPLAY_TOLERANCE = 1e-5  # observation units (metres): replayed observations must agree this closely
METADATA_FILE = "metadata.json"  # Minari's: in the dataset's data/ folder
MAIN_DATA_FILE = "main_data.hdf5"  # Minari's HDF5 file of the episodes
MAX_METADATA_BYTES = 20_000_000  # a dataset's metadata.json (the spaces' bounds are its largest part)
MAX_SPACE_ELEMENTS = 10_000_000  # elements of one box of a recorded space (its bounds are made in memory)
_OPTIONAL_STRING_LISTS = ("author", "author_email", "combined_datasets")  # Minari makes sets of the first two
SPACE_KEYS = ("observation_space", "action_space")  # metadata.json's serialized spaces


ENV_PACKAGES = ("fetchcarry_env", "training")  # entry points of this project's envs live here
TRUSTED_ENV_KWARGS: dict[str, tuple[type, ...]] = {  # keyword arguments of gym.make a dataset may store
    "family": (str,),
    "scenario": (dict,),  # the scenario itself; a path would make the dataset read another file
    "resolution": (int, float),
    "render_mode": (type(None),),  # gym.make records it; replay renders nothing
    "reward": (str,),  # FetchCarryPushPhases-v0: "paper" or "learning" (the env checks the name)
    "gamma": (int, float),  # FetchCarryPushPhases-v0: the learning reward's discount
    "obs_mode": (str,),  # a registered observation mode (the env checks the name)
    "capacity": (str,),  # fetchcarry generate --capacity: "objects=8,..." (only a text Capacity.parse takes)
}


def trusted_env_kwargs() -> dict[str, tuple[type, ...]]:
    """:data:`TRUSTED_ENV_KWARGS` and every observation mode's image options (the env checks their ranges)."""
    images = {o.name: (int,) if o.kind is int else (int, float) if o.kind is float else (str,)
              for mode in modes() for o in mode.options}  # fmt: skip
    return {**TRUSTED_ENV_KWARGS, **images}


class NoSpaceError(InputError):
    """The disk cannot hold the dataset about to be written."""


class UnknownEnvError(InputError):
    """A dataset names an env that is not one of this project's (its env is never made)."""


class DatasetError(InputError):
    """A dataset's files are not what this project writes (an edited or broken ``metadata.json``); names the file."""


def validate_dataset_id(dataset_id: str) -> None:
    """Raise :class:`InputError` unless ``dataset_id`` is a Minari id (``namespace/name-vN``)."""
    from minari.dataset.minari_dataset import parse_dataset_id  # minari (h5py) only when a dataset is used

    try:
        parse_dataset_id(dataset_id)
    except (ValueError, TypeError):  # minari 0.5.4 raises TypeError for an id without -vN
        raise InputError(
            f"dataset id {dataset_id!r} is not a Minari id: use (namespace/)name-v<version>, "
            "e.g. fetchcarry/push-expert-v0"
        ) from None


def dataset_path(dataset_id: str) -> Path:
    return datasets_root() / dataset_id


def dataset_exists(dataset_id: str) -> bool:
    return dataset_path(dataset_id).exists()


def assemble(config: GenerationConfig, staging: Staging) -> Path:
    """Write the Minari dataset ``config.dataset_id`` from its staged episodes ``0 .. episodes-1``.

    The dataset is built in the staging folder; :func:`publish` moves it into place.
    Returns the folder it was built in. A write that fails is an ``OSError`` that
    names that folder, a full disk (h5py says so with a ``RuntimeError``) a
    :class:`NoSpaceError`; either way the half-written folder is removed and the
    staged episodes are kept.
    """
    building = staging.path / ASSEMBLY_FOLDER
    if building.exists():
        shutil.rmtree(building)  # what an interrupted assembly left
    building.mkdir()
    try:
        _write_dataset(config, staging, building)
    except OSError as error:
        shutil.rmtree(building, ignore_errors=True)  # the staged episodes stay; the half-written file goes
        raise OSError(error.errno, f"cannot write the dataset ({error.strerror or error})", str(building)) from error
    except RuntimeError as error:  # h5py reports a failed write (a full disk) as a RuntimeError
        if not any(words in str(error) for words in _DISK_FULL):
            raise
        shutil.rmtree(building, ignore_errors=True)
        raise NoSpaceError(
            f"cannot write the dataset (No space left on device): {building} (the staged episodes are kept: "
            "free some space and run the same command again)"
        ) from None
    namespace = config.dataset_id.rsplit("/", 1)[0] if "/" in config.dataset_id else None
    if namespace is not None:
        from minari.namespace import create_namespace, list_local_namespaces

        if namespace not in list_local_namespaces():
            create_namespace(namespace)
    return building


def _write_dataset(config: GenerationConfig, staging: Staging, building: Path) -> None:
    import minari
    from minari.dataset.minari_storage import MinariStorage

    env = config.source.build_env()
    try:
        storage = MinariStorage.new(
            building / "data",
            observation_space=env.observation_space,
            action_space=env.action_space,
            env_spec=env.spec,
        )
    finally:
        env.close()
    storage.update_metadata(
        {
            "dataset_id": config.dataset_id,
            "minari_version": minari.__version__,
            "algorithm_name": ALGORITHMS[config.source.policy],
            "author": {AUTHOR},
            "code_permalink": CODE_URL,
            "description": _description(config),
            "fetchcarry_generation": config.manifest(),
        }
    )
    episodes = range(config.episodes)
    metadata: list[dict[str, Any]] = []  # filled while the episodes are written: each staged file is read once
    returns: list[tuple[float, float]] = []  # (the episode's return, its do-nothing return), likewise
    storage.update_episodes(_buffers(staging, episodes, metadata, returns))
    storage.update_episode_metadata(metadata, episodes)
    if config.source.policy == "expert" and returns:
        storage.update_metadata(reference_scores(returns))


def reference_scores(returns: list[tuple[float, float]]) -> dict[str, float]:
    """Minari's ``ref_min_score`` and ``ref_max_score`` of an expert dataset: the mean do-nothing return of its
    scenarios and the expert's mean return on them, the benchmark score's 0 and 100, so that
    ``minari.get_normalized_score(dataset, returns)`` is that score over 100 on scenarios of the same family."""
    return {
        "ref_min_score": float(np.mean([floor for _, floor in returns])),
        "ref_max_score": float(np.mean([ret for ret, _ in returns])),
    }


def check_free_space(staging: Staging) -> None:
    """Raise :class:`NoSpaceError` unless the disk of the staging folder can hold the assembled dataset.

    The estimate is the staged files' size times :data:`SPACE_MARGIN` (the HDF5 file
    holds the same arrays, uncompressed) plus :data:`EPISODE_OVERHEAD_BYTES` per episode
    and :data:`MIN_FREE_BYTES`. A write that still fails for want of space is caught by
    :func:`assemble`.
    """
    episodes = len(staging.staged())
    needed = int(staging.size_bytes() * SPACE_MARGIN) + EPISODE_OVERHEAD_BYTES * episodes + MIN_FREE_BYTES
    free = shutil.disk_usage(staging.path).free
    if free < needed:
        raise NoSpaceError(
            f"not enough free space to assemble {staging.dataset_id!r} in {staging.path}: about "
            f"{needed / 1e6:.1f} MB needed, {free / 1e6:.1f} MB free (the staged episodes are kept: "
            "free some space and run the same command again)"
        )


def publish(built: Path, dataset_id: str, aside: Path) -> None:
    """Move the dataset built in ``built`` to its place; an existing dataset is replaced in one atomic step.

    Where the file system can exchange two folders atomically (Linux ``renameat2``),
    the old and the new dataset swap places and the old one is deleted. Elsewhere the
    old one is first renamed to ``aside`` (same file system), then the new one moved
    in; a run interrupted between the two renames is repaired by
    :func:`recover_replaced` (the old dataset is put back).
    """
    final = dataset_path(dataset_id)
    final.parent.mkdir(parents=True, exist_ok=True)
    if not final.exists():
        os.rename(built, final)
        return
    if _exchange(built, final):
        shutil.rmtree(built)  # now the old dataset
        return
    if aside.exists():
        shutil.rmtree(aside)
    os.rename(final, aside)
    os.rename(built, final)
    shutil.rmtree(aside)


def recover_replaced(dataset_id: str, aside: Path) -> None:
    """Undo a replacement interrupted between its two renames (see :func:`publish`)."""
    if not aside.exists():
        return
    final = dataset_path(dataset_id)
    if final.exists():
        shutil.rmtree(aside)
    else:
        os.rename(aside, final)


def finished_with(dataset_id: str, manifest: dict[str, Any], episodes: int) -> bool:
    """Whether dataset ``dataset_id`` is there, whole, made with ``manifest``'s options and ``episodes`` episodes."""
    file = dataset_path(dataset_id) / "data" / "metadata.json"
    try:
        metadata = json.loads(file.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return False
    return (
        isinstance(metadata, dict)
        and metadata.get("fetchcarry_generation") == manifest
        and metadata.get("total_episodes") == episodes
    )


def _exchange(first: Path, second: Path) -> bool:
    """Swap two paths atomically with Linux's ``renameat2(RENAME_EXCHANGE)``; ``False`` where it is not available."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    result = renameat2(_AT_FDCWD, os.fsencode(first), _AT_FDCWD, os.fsencode(second), _RENAME_EXCHANGE)
    if result == 0:
        return True
    error = ctypes.get_errno()
    if error in (errno.ENOSYS, errno.EINVAL, errno.EXDEV, errno.ENOTSUP):
        return False
    raise OSError(error, os.strerror(error), str(second))


def _description(config: GenerationConfig) -> str:
    source = config.source
    return (
        f"{config.episodes} episodes of {source.gym_id} ({source.label}) by the {source.policy} policy; "
        f"episode k uses seed {source.seed} + k. Episode metadata holds the seed, the scenario JSON and the "
        "episode's figures; per-step infos hold the planner's figures."
    )


def _buffers(
    staging: Staging, episodes: range, metadata: list[dict[str, Any]], returns: list[tuple[float, float]]
) -> Iterator[Any]:
    """Minari's buffer of each staged episode; appends each episode's metadata to ``metadata`` and its return and
    do-nothing return to ``returns``."""
    from minari.data_collector import EpisodeBuffer

    for k in episodes:
        record = staging.read(k)
        metadata.append(_episode_metadata(record))
        returns.append((float(np.sum(record.rewards)), do_nothing_return(len(record.scenario["objects"]))))
        yield EpisodeBuffer(
            id=k,
            seed=record.seed,
            observations=record.observations,
            actions=record.actions,
            rewards=record.rewards,
            terminations=record.terminations,
            truncations=record.truncations,
            infos={key: value for key, value in record.infos.items() if not is_timing(key)},
        )


def _episode_metadata(record: EpisodeRecord) -> dict[str, Any]:
    """HDF5 attributes of an episode: the scenario JSON and the figures (``None`` is stored as NaN)."""
    metadata: dict[str, Any] = {"scenario": json.dumps(record.scenario)}
    if PROJECTED_INFO in record.infos:  # phases: expert moves projected onto their nearest candidate
        metadata["projected"] = int(np.count_nonzero(record.infos[PROJECTED_INFO]))
    for key, value in record.figures.to_dict().items():
        if key == "seed" or is_timing(key):
            continue  # Minari stores the seed itself; wall-clock times would make each run's file differ
        key = "scenario_name" if key == "scenario" else key
        metadata[key] = float("nan") if value is None else value
    return metadata


# -- reading ---------------------------------------------------------------------------------


def load(dataset_id: str):
    """The Minari dataset ``dataset_id``, its ``metadata.json`` checked before Minari reads any of it.

    Minari itself (``minari.load_dataset``) ``gym.make``s the env a dataset names when a
    space is missing from its metadata, which would run whatever entry point an edited
    file names. Here the metadata is checked first (:func:`check_metadata`: every key
    Minari reads, the env spec trusted, both spaces present and sane, the HDF5 file's
    episodes those it counts, no link in it followed) and the storage is built from the
    spaces read here, so no code of Minari's ever makes an env and Minari reads nothing
    outside the dataset's files. A bad file is a :class:`DatasetError` naming it.
    """
    from minari import MinariDataset
    from minari.dataset._storages import get_minari_storage

    validate_dataset_id(dataset_id)
    data = dataset_path(dataset_id) / "data"
    if not data.exists():
        raise InputError(f"no dataset {dataset_id!r} under {datasets_root()} (set MINARI_DATASETS_PATH?)")
    observation_space, action_space = check_metadata(dataset_id)
    storage = get_minari_storage("hdf5")(data, observation_space, action_space)
    return MinariDataset(storage)


def check_metadata(dataset_id: str) -> tuple[gym.Space, gym.Space]:
    """The observation and action spaces of dataset ``dataset_id``, once its ``metadata.json`` is found sane.

    Checks, before Minari reads the file: the keys Minari reads and their types, the
    Minari version, the env spec (it must pass :func:`trusted_env_spec`, and so must an
    ``eval_env_spec``), both spaces (present, of sane size, readable), and that the HDF5
    file holds the episodes and steps the metadata counts, as plain groups and datasets of
    those spaces that read nothing outside the file (:func:`_check_main_data`). Raises
    :class:`DatasetError` naming the file (or :class:`UnknownEnvError`); an unreadable
    file is an ``OSError`` naming it.
    """
    file = dataset_path(dataset_id) / "data" / METADATA_FILE
    try:
        metadata = read_json(file, MAX_METADATA_BYTES)
    except JsonInputError as problem:
        raise DatasetError(_metadata_problem(file, str(problem))) from None
    if not isinstance(metadata, dict):
        raise DatasetError(_metadata_problem(file, "not a JSON object"))
    with file.open("rb") as stream:
        if stream.read(len(codecs.BOM_UTF8)) == codecs.BOM_UTF8:  # Minari reads the file without one
            raise DatasetError(_metadata_problem(file, "it starts with a byte order mark"))
    _check_metadata_fields(file, metadata)
    for key in ("env_spec", "eval_env_spec"):
        if metadata.get(key) is not None:
            try:
                trusted_env_spec(_env_spec(file, key, metadata[key]), dataset_id)
            except UnknownEnvError as error:
                raise UnknownEnvError(f"{file}: {error}") from None
    observation_space, action_space = (_space(file, key, metadata.get(key)) for key in SPACE_KEYS)
    _check_main_data(dataset_id, file, metadata, observation_space, action_space)
    return observation_space, action_space


def _metadata_problem(file: Path, problem: str) -> str:
    return f"{file}: {problem} (this dataset's metadata is not what fetchcarry writes: generate it again)"


def _check_metadata_fields(file: Path, metadata: dict[str, Any]) -> None:
    """Every key Minari reads from ``metadata.json``, with the type it assumes."""
    from minari import supported_dataset_versions

    for key in ("total_episodes", "total_steps"):
        value = metadata.get(key)
        if not isinstance(value, int) or isinstance(value, bool) or value < 0:
            raise DatasetError(_metadata_problem(file, f"{key} must be a whole number >= 0, not {describe(value)}"))
    for key in ("dataset_id", "minari_version", "env_spec"):
        if not isinstance(metadata.get(key), str):
            raise DatasetError(_metadata_problem(file, f"{key} must be a string, not {describe(metadata.get(key))}"))
    version = metadata["minari_version"]
    if version not in supported_dataset_versions:
        readable = ", ".join(sorted(supported_dataset_versions))
        raise DatasetError(_metadata_problem(file, f"minari_version {describe(version)} is not one of {readable}"))
    if metadata.get("data_format", "hdf5") != "hdf5":
        raise DatasetError(
            _metadata_problem(file, f'data_format must be "hdf5", not {describe(metadata["data_format"])}')
        )
    if not isinstance(metadata.get("jpeg_encoding", True), bool):
        raise DatasetError(_metadata_problem(file, "jpeg_encoding must be true or false"))
    if metadata.get("eval_env_spec") is not None and not isinstance(metadata["eval_env_spec"], str):
        raise DatasetError(_metadata_problem(file, "eval_env_spec must be a string"))
    for key in _OPTIONAL_STRING_LISTS:
        value = metadata.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise DatasetError(_metadata_problem(file, f"{key} must be a list of strings, not {describe(value)}"))
    size = metadata.get("dataset_size", 0.0)
    if not isinstance(size, int | float) or isinstance(size, bool) or not math.isfinite(size):
        raise DatasetError(_metadata_problem(file, f"dataset_size must be a number, not {describe(size)}"))


def _env_spec(file: Path, key: str, text: str) -> Any:
    """The ``EnvSpec`` of the JSON text ``text`` (Minari's own reading of it); :class:`DatasetError` if it is none."""
    text = (  # what Minari removes for gymnasium 1.0 before it reads the spec
        text.replace('"order_enforce": true,', "")
        .replace('"apply_api_compatibility": false,', "")
        .replace('"autoreset": false, ', "")
    )
    try:
        parse_json(text)  # the size, nesting and number checks of every JSON this project reads
        spec = EnvSpec.from_json(text)
    except Exception as error:
        raise DatasetError(_metadata_problem(file, f"{key} is not an env spec ({type(error).__name__})")) from None
    if not isinstance(spec.id, str) or not isinstance(spec.kwargs, dict):
        raise DatasetError(_metadata_problem(file, f"{key} is not an env spec (an id and keyword arguments)"))
    return spec


def _space(file: Path, key: str, text: Any) -> gym.Space:
    """The space serialized as ``text``; :class:`DatasetError` when it is missing, too large or not a space."""
    from minari.serialization import deserialize_space

    if not isinstance(text, str):
        raise DatasetError(_metadata_problem(file, f"{key} must be a serialized space, not {describe(text)}"))
    try:
        _check_space_size(parse_json(text))
        space = deserialize_space(text)
    except DatasetError as error:
        raise DatasetError(_metadata_problem(file, f"{key}: {error}")) from None
    except Exception as error:
        raise DatasetError(_metadata_problem(file, f"{key} is not a space ({type(error).__name__})")) from None
    if not isinstance(space, gym.spaces.Space):
        raise DatasetError(_metadata_problem(file, f"{key} is not a space"))
    return space


def _check_space_size(value: Any, depth: int = 0) -> None:
    """Refuse a serialized space that nests too deeply or whose box would not fit in memory."""
    if depth > 20:
        raise DatasetError("nested too deeply")
    if isinstance(value, dict):
        shape = value.get("shape")
        if isinstance(shape, list):
            if not all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in shape):
                raise DatasetError(f"a shape of {describe(shape)}")
            if math.prod(shape) > MAX_SPACE_ELEMENTS:
                raise DatasetError(f"a shape of {describe(shape)}: more than {MAX_SPACE_ELEMENTS:,} elements")
        children = value.values()
    elif isinstance(value, list):
        children = value
    else:
        return
    for child in children:
        _check_space_size(child, depth + 1)


def _check_main_data(
    dataset_id: str, file: Path, metadata: dict[str, Any], observation_space: gym.Space, action_space: gym.Space
) -> None:
    """Raise :class:`DatasetError` unless the HDF5 file next to ``file`` holds the episodes ``metadata`` counts.

    :func:`training.data.hdf5_checks.check_episode_file`: episodes ``0 .. total_episodes-1``
    of ``total_steps`` steps in all, plain groups and datasets of the recorded spaces, and
    nothing that makes a reader read outside the file (a link, external storage, a
    virtual dataset) or more than it holds. No link is followed.
    """
    from training.data.hdf5_checks import (  # h5py only when a dataset is read
        EpisodeCountError,
        EpisodeFileError,
        Spaces,
        check_episode_file,
    )

    main = file.parent / MAIN_DATA_FILE
    spaces = Spaces(observation_space, action_space)  # images as JPEG bytes: how the storage of load() reads them
    try:
        check_episode_file(main, metadata["total_episodes"], metadata["total_steps"], spaces)
    except FileNotFoundError:
        raise DatasetError(f"dataset {dataset_id!r}: {main}: no such file (the dataset's episodes)") from None
    except EpisodeCountError as problem:  # the two files disagree: name both
        raise DatasetError(_metadata_problem(file, f"{MAIN_DATA_FILE}: {problem}")) from None
    except EpisodeFileError as problem:
        raise DatasetError(
            f"dataset {dataset_id!r}: {main}: {problem} (this dataset's episodes are not what fetchcarry writes: "
            "generate it again)"
        ) from None


def episode_metadata(dataset, episode: int) -> dict[str, Any]:
    """Episode ``episode``'s metadata: ``seed``, ``scenario`` (a dict) and its figures."""
    if not 0 <= episode < dataset.total_episodes:
        raise InputError(f"episode {episode} out of range: the dataset has {dataset.total_episodes} episodes")
    metadata = next(iter(dataset.storage.get_episode_metadata([episode])))
    metadata = {k: _plain(v) for k, v in metadata.items()}
    metadata["scenario"] = json.loads(metadata["scenario"])
    return metadata


def _plain(value: Any) -> Any:
    """A plain Python value from an HDF5 attribute (NaN stands for None: HDF5 has no null)."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, float) and math.isnan(value):
        return None
    return value


def info(dataset_id: str) -> dict[str, Any]:
    """A summary of a dataset: size, env, policy, outcomes and the planner's figures."""
    dataset = load(dataset_id)
    metadata = dataset.storage.metadata
    episodes = [episode_metadata(dataset, k) for k in range(dataset.total_episodes)]
    spec = dataset.spec.env_spec
    kwargs = dict(spec.kwargs) if spec is not None else {}
    scenario = kwargs.get("scenario")
    steps = np.array([e["steps"] for e in episodes])
    projected = [int(e["projected"]) for e in episodes if "projected" in e]
    return {
        "dataset_id": dataset_id,
        "path": str(dataset_path(dataset_id)),
        "env_id": spec.id if spec is not None else None,
        "family": kwargs.get("family"),
        "scenario": str(scenario.get("name")) if isinstance(scenario, dict) else None,
        "algorithm": metadata.get("algorithm_name"),
        "generation": metadata.get("fetchcarry_generation"),
        "episodes": dataset.total_episodes,
        "steps": dataset.total_steps,
        "seeds": [min(e["seed"] for e in episodes), max(e["seed"] for e in episodes)],
        "success_rate": float(np.mean([bool(e["success"]) for e in episodes])),
        "outcomes": dict(Counter(e["outcome"] for e in episodes)),
        "mean_steps": float(steps.mean()),
        "plans": int(sum(e["plans"] for e in episodes)),
        "replans": int(sum(e["replans"] for e in episodes)),
        "repairs": int(sum(e["repairs"] for e in episodes)),
        "planner_failures": int(sum(e["planner_failures"] for e in episodes)),
        # phases datasets: expert moves recorded as their nearest move candidate (None when not recorded)
        "projected_moves": sum(projected) if len(projected) == len(episodes) else None,
        "size_mb": float(metadata.get("dataset_size", 0.0)),
    }


@dataclass(frozen=True)
class ReplayReport:
    """How a replay of a recorded episode compared with the recording."""

    dataset_id: str
    episode: int
    seed: int
    steps: int
    same_scenario: bool  # the env drew the recorded scenario from the seed
    max_observation_error: float  # largest absolute difference over every observation (metres)
    first_divergence: int | None  # first state index whose observation differs beyond the tolerance
    same_rewards: bool
    same_final_state: bool
    reproduced: bool  # all of the above agree

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def replay(dataset_id: str, episode: int, tolerance: float = REPLAY_TOLERANCE) -> ReplayReport:
    """Re-run episode ``episode`` in the recovered env from its seed and recorded actions; compare."""
    dataset = load(dataset_id)
    metadata = episode_metadata(dataset, episode)
    env = make_recorded_env(dataset, dataset_id)  # first: it checks the spaces the episode is decoded with
    try:
        data = dataset[episode]
        observation, _ = env.reset(seed=metadata["seed"])
        same_scenario = env.unwrapped.scenario.to_dict() == metadata["scenario"]
        errors = [_observation_error(observation, data.observations, 0)]
        rewards = []
        for t, action in enumerate(data.actions):
            observation, reward, _, _, _ = env.step(action)
            errors.append(_observation_error(observation, data.observations, t + 1))
            rewards.append(reward)
    finally:
        env.close()
    diverged = [k for k, e in enumerate(errors) if e > tolerance]
    same_rewards = bool(np.allclose(rewards, data.rewards, atol=1e-6))
    same_final = errors[-1] <= tolerance
    return ReplayReport(
        dataset_id=dataset_id,
        episode=episode,
        seed=int(metadata["seed"]),
        steps=len(data.actions),
        same_scenario=same_scenario,
        max_observation_error=float(max(errors)),
        first_divergence=diverged[0] if diverged else None,
        same_rewards=same_rewards,
        same_final_state=same_final,
        reproduced=same_scenario and not diverged and same_rewards,
    )


def _trusted_value(key: str, value: Any) -> bool:
    """A capacity is a text :meth:`Capacity.parse` takes (bounded counts); other values need no more check here."""
    if key != "capacity":
        return True
    try:
        Capacity.parse(value)
    except InputError:
        return False
    return True


def trusted_env_spec(spec: Any, dataset_id: str) -> tuple[str, dict[str, Any]]:
    """The env id and ``gym.make`` keyword arguments of a dataset's env spec, if it is one of this project's envs.

    Raises :class:`UnknownEnvError` unless the id is registered with an entry point in
    this project's packages, the spec names that same entry point, it adds no wrappers,
    and every keyword argument is one of :func:`trusted_env_kwargs` with a plain value.
    """
    ours = sorted(k for k, v in gym.envs.registry.items() if _is_ours(v.entry_point))
    if spec is None:
        raise UnknownEnvError(f"dataset {dataset_id!r} names no env: it cannot be replayed")
    registered = gym.envs.registry.get(spec.id) if isinstance(spec.id, str) else None
    if registered is None or not _is_ours(registered.entry_point) or spec.entry_point != registered.entry_point:
        raise UnknownEnvError(
            f"dataset {dataset_id!r} names an unknown env {spec.id!r} (entry point {spec.entry_point!r}); "
            f"only this project's envs are rebuilt: {', '.join(ours)}"
        )
    kwargs, trusted = dict(spec.kwargs or {}), trusted_env_kwargs()
    for key, value in kwargs.items():
        allowed = trusted.get(key)
        if (
            allowed is None
            or isinstance(value, bool)
            or not isinstance(value, allowed)
            or not _trusted_value(key, value)
        ):
            raise UnknownEnvError(
                f"dataset {dataset_id!r} names an unknown env: {spec.id} does not take {key}={value!r:.60} "
                f"from a dataset (allowed: {', '.join(trusted)})"
            )
    if spec.additional_wrappers and tuple(spec.additional_wrappers) != _own_wrappers(spec.id, kwargs):
        names = ", ".join(str(w.name) for w in spec.additional_wrappers)
        raise UnknownEnvError(f"dataset {dataset_id!r} names an unknown env: it adds wrappers ({names})")
    return spec.id, kwargs


def _own_wrappers(env_id: str, kwargs: dict[str, Any]) -> tuple[Any, ...]:
    """The wrappers this project's entry point itself puts around the env (``FetchCarryPushPhases-v0``'s)."""
    try:
        env = make_env(env_id=env_id, **kwargs)
    except Exception:  # kwargs the env refuses: not its own wrappers either
        return ()
    try:
        return tuple(env.spec.additional_wrappers) if env.spec is not None else ()
    finally:
        env.close()


def make_recorded_env(dataset: Any, dataset_id: str):
    """The env a dataset was recorded in, made from this project's registry (see :func:`trusted_env_spec`).

    Raises :class:`DatasetError` when the dataset's spaces are not the env's (its
    episodes would be decoded with the wrong shapes).
    """
    env_id, kwargs = trusted_env_spec(dataset.spec.env_spec, dataset_id)
    env = make_env(env_id=env_id, **kwargs)
    if env.observation_space != dataset.observation_space or env.action_space != dataset.action_space:
        env.close()
        file = dataset_path(dataset_id) / "data" / METADATA_FILE
        raise DatasetError(_metadata_problem(file, f"its spaces are not those of {env_id}, the env it names"))
    return env


def _is_ours(entry_point: Any) -> bool:
    return isinstance(entry_point, str) and entry_point.split(":")[0].split(".")[0] in ENV_PACKAGES


def _observation_error(observation: dict[str, np.ndarray], recorded: dict[str, np.ndarray], index: int) -> float:
    return max(
        float(np.max(np.abs(np.asarray(observation[k], dtype=np.float64) - recorded[k][index]))) for k in recorded
    )  # float64: an image's uint8 difference would wrap around
