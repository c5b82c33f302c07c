"""``fetchcarry dataset render``: a dataset's episodes replayed into another observation mode.

A dataset stores what the env observed (by default the state: the geometry vector and the
goals). Its episodes replay bit for bit from their seeds and actions
(:func:`training.data.datasets.replay`), so any observation the env can make can be had
afterwards, as ManiSkill replays state demonstrations into any observation mode:
:func:`render_dataset` resets an env of the same id and options in ``obs_mode`` with
each episode's seed, steps the recorded actions, checks at every state that the state
keys (``observation``, ``achieved_goal``, ``desired_goal``) and the rewards equal the
recorded ones exactly, and writes a new dataset with the same actions, rewards, flags,
per-step infos and episode metadata, and the new observations. The new dataset's
metadata names its origin (``fetchcarry_render``).

An episode that does not replay exactly stops the render with :class:`RenderError`
(bad input: the dataset is not what this project's env makes); nothing is written.
"""

from __future__ import annotations

import shutil
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm import tqdm

from fetchcarry_env.errors import InputError
from fetchcarry_env.observations import image_option_names, mode_names
from training.data.datasets import (
    AUTHOR,
    REPLACED_FOLDER,
    dataset_exists,
    dataset_path,
    episode_metadata,
    load,
    publish,
    recover_replaced,
    trusted_env_spec,
    validate_dataset_id,
)
from training.data.staging import DatasetLock, Staging
from training.envs import make_env

STATE_KEYS = ("observation", "achieved_goal", "desired_goal")  # what every mode observes, recorded or not
RENDER_FOLDER = "rendering"  # in the new id's staging folder: the dataset being written


class RenderError(InputError):
    """A dataset's episode does not replay exactly, so it cannot be rendered into another mode."""


@dataclass(frozen=True)
class RenderReport:
    """What a render made: the new dataset, its mode, episodes and steps, and how long it took."""

    dataset_id: str
    source_id: str
    obs_mode: str
    episodes: int
    steps: int
    wall_s: float
    size_mb: float  # the new dataset's files


def render_dataset(
    dataset_id: str,
    obs_mode: str,
    out_id: str,
    *,
    image_options: dict[str, Any] | None = None,
    overwrite: bool = False,
    progress: bool = True,
) -> RenderReport:
    """Replay dataset ``dataset_id`` into ``obs_mode`` as the new dataset ``out_id`` (see the module docstring).

    ``image_options``: the env's image options (``topdown_size``, ``camera_size``, ...).
    Raises :class:`InputError` for an unknown mode, the same id twice, an existing
    ``out_id`` (unless ``overwrite``), and :class:`RenderError` for an episode that
    does not replay exactly.
    """
    if obs_mode not in mode_names():
        raise InputError(f"unknown observation mode {obs_mode!r}: choose one of {', '.join(mode_names())}")
    validate_dataset_id(dataset_id)
    validate_dataset_id(out_id)
    if out_id == dataset_id:
        raise InputError("the rendered dataset needs a new id (--out): a dataset is never rendered over itself")
    started = time.perf_counter()
    source = load(dataset_id)
    env_id, kwargs = trusted_env_spec(source.spec.env_spec, dataset_id)
    kwargs = {k: v for k, v in kwargs.items() if k != "obs_mode" and k not in image_option_names()}
    if obs_mode != "state":
        kwargs.update(obs_mode=obs_mode, **(image_options or {}))
    try:
        env = make_env(env_id=env_id, **kwargs)
    except (TypeError, ValueError) as error:
        raise InputError(f"cannot make {env_id} in obs_mode {obs_mode!r}: {error}") from None
    with DatasetLock(out_id):
        if dataset_exists(out_id) and not overwrite:
            raise InputError(f"dataset {out_id!r} exists: choose another id, or pass --overwrite to replace it")
        staging = Staging(out_id)
        recover_replaced(out_id, staging.path / REPLACED_FOLDER)
        building = staging.path / RENDER_FOLDER
        if building.exists():
            shutil.rmtree(building)
        building.mkdir(parents=True)
        try:
            steps = _write(source, dataset_id, out_id, env, building, progress)
        except BaseException:
            shutil.rmtree(building, ignore_errors=True)
            raise
        finally:
            env.close()
        publish(building, out_id, staging.path / REPLACED_FOLDER)
        shutil.rmtree(staging.path, ignore_errors=True)
    size = sum(f.stat().st_size for f in dataset_path(out_id).rglob("*") if f.is_file())
    return RenderReport(
        out_id, dataset_id, obs_mode, source.total_episodes, steps, time.perf_counter() - started, size / 1e6
    )


def _write(source: Any, dataset_id: str, out_id: str, env: gym.Env, building: Any, progress: bool) -> int:
    """Write the rendered dataset into ``building``; the number of steps written."""
    import minari
    from minari.dataset.minari_storage import MinariStorage

    storage = MinariStorage.new(
        building / "data", observation_space=env.observation_space, action_space=env.action_space, env_spec=env.spec
    )
    old = source.storage.metadata
    storage.update_metadata(
        {
            "dataset_id": out_id,
            "minari_version": minari.__version__,
            "algorithm_name": old.get("algorithm_name", "unknown"),
            "author": {AUTHOR},
            "code_permalink": old.get("code_permalink", ""),
            "description": f"{old.get('description', '')} Rendered from {dataset_id} into obs_mode "
            f"{env.unwrapped.obs_mode!r} (fetchcarry dataset render).",
            "fetchcarry_generation": old.get("fetchcarry_generation", {}),
            "fetchcarry_render": {"from": dataset_id, "obs_mode": env.unwrapped.obs_mode},
        }
    )
    episodes = range(source.total_episodes)
    metadata: list[dict[str, Any]] = []
    steps = [0]
    bar = tqdm(
        total=len(episodes), desc="rendering", unit="episode", disable=None if progress else True, file=sys.stderr
    )
    with bar:
        storage.update_episodes(_buffers(source, dataset_id, env, episodes, metadata, steps, bar))
    storage.update_episode_metadata(metadata, episodes)
    return steps[0]


def _buffers(
    source: Any, dataset_id: str, env: gym.Env, episodes: range, metadata: list, steps: list[int], bar: tqdm
) -> Iterator[Any]:
    """Minari's buffer of each episode replayed in ``env``; the episodes' metadata is copied into ``metadata``."""
    from minari.data_collector import EpisodeBuffer

    for k in episodes:
        recorded = source[k]
        meta = episode_metadata(source, k)
        observations = replay_observations(env, recorded, meta, dataset_id, k)
        raw = next(iter(source.storage.get_episode_metadata([k])))
        metadata.append({key: value for key, value in raw.items() if key not in ("seed", "id")})
        steps[0] += len(recorded.actions)
        bar.update()
        yield EpisodeBuffer(
            id=k,
            seed=meta["seed"],
            observations=observations,
            actions=recorded.actions,
            rewards=recorded.rewards,
            terminations=recorded.terminations,
            truncations=recorded.truncations,
            infos=recorded.infos,
        )


def replay_observations(env: gym.Env, recorded: Any, meta: dict[str, Any], dataset_id: str, k: int) -> dict:
    """Every observation of episode ``k`` replayed in ``env`` (a dict of stacked arrays, the reset's first).

    :class:`RenderError` unless the scenario, the state keys and the rewards are the recorded ones exactly.
    """
    where = f"episode {k} of {dataset_id}"
    observation, _ = env.reset(seed=int(meta["seed"]))
    if env.unwrapped.scenario.to_dict() != meta["scenario"]:
        raise RenderError(f"{where}: the env does not draw the recorded scenario from seed {meta['seed']}")
    seen = [observation]
    _check_state(observation, recorded.observations, 0, where)
    for t, action in enumerate(recorded.actions):
        observation, reward, _, _, _ = env.step(action)
        _check_state(observation, recorded.observations, t + 1, where)
        if reward != recorded.rewards[t]:
            raise RenderError(f"{where}: step {t} gives reward {reward!r}, recorded {recorded.rewards[t]!r}")
        seen.append(observation)
    return {key: np.stack([o[key] for o in seen]) for key in seen[0]}


def _check_state(observation: dict, recorded: dict, index: int, where: str) -> None:
    for key in STATE_KEYS:
        if not np.array_equal(observation[key], recorded[key][index]):
            raise RenderError(f"{where}: the replayed {key} differs from the recorded one at state {index}")
