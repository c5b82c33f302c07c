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
  ``planning_s``, ``plans``, ``replans``, ``planner_failures``, ``objective``, ...);
- per-step infos (:data:`training.rollout.INFO_KEYS`): the seconds the planner took
  before each step, whether it planned or replanned, whether the action was the
  fallback, refused, or stopped at a contact, and how many objects are delivered.
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

import fetchcarry_env  # noqa: F401  (registers this project's env ids: recovering and rebuilding a dataset's env)
from fetchcarry_env.errors import UsageError
from training.data.sources import GenerationConfig
from training.data.staging import Staging, datasets_root
from training.policies.phase_expert import PROJECTED_INFO
from training.rollout import EpisodeRecord

AUTHOR = "fetchcarry"
CODE_URL = "https://github.com/fetchcarry/fetchcarry"
ALGORITHMS = {"expert": "fetchcarry MILP expert (SCIP), ExpertPolicy", "random": "RandomMaskedPolicy"}
ASSEMBLY_FOLDER = "assembling"  # in the staging folder: the dataset being written
REPLACED_FOLDER = "replaced"  # in the staging folder: an old dataset between the two renames of a replacement
SPACE_MARGIN = 1.2  # assembled dataset size / staged files' size (HDF5 holds the same arrays)
MIN_FREE_BYTES = 1_000_000  # bytes kept free besides the estimate
_AT_FDCWD = -100  # Linux: paths relative to the current directory
_RENAME_EXCHANGE = 2  # Linux renameat2 flag: swap the two paths
REPLAY_TOLERANCE = 1e-5  # observation units (metres): replayed observations must agree this closely


ENV_PACKAGES = ("fetchcarry_env", "training")  # entry points of this project's envs live here
TRUSTED_ENV_KWARGS: dict[str, tuple[type, ...]] = {  # keyword arguments of gym.make a dataset may store
    "family": (str,),
    "scenario": (dict,),  # the scenario itself; a path would make the dataset read another file
    "resolution": (int, float),
    "render_mode": (type(None),),  # gym.make records it; replay renders nothing
    "reward": (str,),  # FetchCarryPushPhases-v0: "paper" or "learning" (the env checks the name)
    "gamma": (int, float),  # FetchCarryPushPhases-v0: the learning reward's discount
}


class NoSpaceError(UsageError):
    """The disk cannot hold the dataset about to be written."""


class UnknownEnvError(UsageError):
    """A dataset names an env that is not one of this project's (its env is never made)."""


def validate_dataset_id(dataset_id: str) -> None:
    """Raise :class:`UsageError` unless ``dataset_id`` is a Minari id (``namespace/name-vN``)."""
    from minari.dataset.minari_dataset import parse_dataset_id  # minari (h5py) only when a dataset is used

    try:
        parse_dataset_id(dataset_id)
    except (ValueError, TypeError):  # minari 0.5.4 raises TypeError for an id without -vN
        raise UsageError(
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
    Returns the folder it was built in. A write that fails (a full disk) is an
    ``OSError`` that names that folder.
    """
    building = staging.path / ASSEMBLY_FOLDER
    if building.exists():
        shutil.rmtree(building)  # what an interrupted assembly left
    building.mkdir()
    try:
        _write_dataset(config, staging, building)
    except OSError as error:
        raise OSError(error.errno, f"cannot write the dataset ({error.strerror or error})", str(building)) from error
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
    storage.update_episodes(_buffers(staging, episodes, metadata))
    storage.update_episode_metadata(metadata, episodes)


def check_free_space(staging: Staging) -> None:
    """Raise :class:`NoSpaceError` unless the disk of the staging folder can hold the assembled dataset.

    The estimate is the staged files' size times :data:`SPACE_MARGIN` (the HDF5 file
    holds the same arrays, uncompressed, plus the per-episode metadata).
    """
    needed = int(staging.size_bytes() * SPACE_MARGIN) + MIN_FREE_BYTES
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


def _buffers(staging: Staging, episodes: range, metadata: list[dict[str, Any]]) -> Iterator[Any]:
    """Minari's buffer of each staged episode; appends each episode's metadata to ``metadata``."""
    from minari.data_collector import EpisodeBuffer

    for k in episodes:
        record = staging.read(k)
        metadata.append(_episode_metadata(record))
        yield EpisodeBuffer(
            id=k,
            seed=record.seed,
            observations=record.observations,
            actions=record.actions,
            rewards=record.rewards,
            terminations=record.terminations,
            truncations=record.truncations,
            infos=record.infos,
        )


def _episode_metadata(record: EpisodeRecord) -> dict[str, Any]:
    """HDF5 attributes of an episode: the scenario JSON and the figures (``None`` is stored as NaN)."""
    metadata: dict[str, Any] = {"scenario": json.dumps(record.scenario)}
    if PROJECTED_INFO in record.infos:  # phases: expert moves projected onto their nearest candidate
        metadata["projected"] = int(np.count_nonzero(record.infos[PROJECTED_INFO]))
    for key, value in record.figures.to_dict().items():
        if key == "seed":
            continue  # Minari stores the seed itself
        key = "scenario_name" if key == "scenario" else key
        metadata[key] = float("nan") if value is None else value
    return metadata


# -- reading ---------------------------------------------------------------------------------


def load(dataset_id: str):
    """``minari.load_dataset(dataset_id)`` with a clear error when it is not there."""
    import minari

    validate_dataset_id(dataset_id)
    if not (dataset_path(dataset_id) / "data").exists():
        raise UsageError(f"no dataset {dataset_id!r} under {datasets_root()} (set MINARI_DATASETS_PATH?)")
    return minari.load_dataset(dataset_id)


def episode_metadata(dataset, episode: int) -> dict[str, Any]:
    """Episode ``episode``'s metadata: ``seed``, ``scenario`` (a dict) and its figures."""
    if not 0 <= episode < dataset.total_episodes:
        raise UsageError(f"episode {episode} out of range: the dataset has {dataset.total_episodes} episodes")
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
    planning = np.array([e["planning_s"] for e in episodes])
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
        "mean_planning_s": float(planning.mean()),
        "max_planning_s": float(planning.max()),
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
    data = dataset[episode]
    env = make_recorded_env(dataset, dataset_id)
    try:
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


def trusted_env_spec(spec: Any, dataset_id: str) -> tuple[str, dict[str, Any]]:
    """The env id and ``gym.make`` keyword arguments of a dataset's env spec, if it is one of this project's envs.

    Raises :class:`UnknownEnvError` unless the id is registered with an entry point in
    this project's packages, the spec names that same entry point, it adds no wrappers,
    and every keyword argument is one of :data:`TRUSTED_ENV_KWARGS` with a plain value.
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
    kwargs = dict(spec.kwargs or {})
    for key, value in kwargs.items():
        allowed = TRUSTED_ENV_KWARGS.get(key)
        if allowed is None or isinstance(value, bool) or not isinstance(value, allowed):
            raise UnknownEnvError(
                f"dataset {dataset_id!r} names an unknown env: {spec.id} does not take {key}={value!r:.60} "
                f"from a dataset (allowed: {', '.join(TRUSTED_ENV_KWARGS)})"
            )
    if spec.additional_wrappers and tuple(spec.additional_wrappers) != _own_wrappers(spec.id, kwargs):
        names = ", ".join(str(w.name) for w in spec.additional_wrappers)
        raise UnknownEnvError(f"dataset {dataset_id!r} names an unknown env: it adds wrappers ({names})")
    return spec.id, kwargs


def _own_wrappers(env_id: str, kwargs: dict[str, Any]) -> tuple[Any, ...]:
    """The wrappers this project's entry point itself puts around the env (``FetchCarryPushPhases-v0``'s)."""
    try:
        env = gym.make(env_id, **kwargs)
    except Exception:  # kwargs the env refuses: not its own wrappers either
        return ()
    try:
        return tuple(env.spec.additional_wrappers) if env.spec is not None else ()
    finally:
        env.close()


def make_recorded_env(dataset: Any, dataset_id: str):
    """The env a dataset was recorded in, made from this project's registry (see :func:`trusted_env_spec`)."""
    env_id, kwargs = trusted_env_spec(dataset.spec.env_spec, dataset_id)
    return gym.make(env_id, **kwargs)


def _is_ours(entry_point: Any) -> bool:
    return isinstance(entry_point, str) and entry_point.split(":")[0].split(".")[0] in ENV_PACKAGES


def _observation_error(observation: dict[str, np.ndarray], recorded: dict[str, np.ndarray], index: int) -> float:
    return max(float(np.max(np.abs(np.asarray(observation[k]) - recorded[k][index]))) for k in recorded)
