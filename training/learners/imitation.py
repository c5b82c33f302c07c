"""Behaviour cloning into a run folder: demonstrations from a Minari dataset, resumable epochs.

:func:`demonstrations_from_dataset` reads a dataset recorded in the candidate-phase
interface (``fetchcarry generate --interface phases``): its actions are candidate
indices and its per-step info ``action_mask`` holds each state's mask, so nothing but
the dataset is needed. Steps whose action the mask does not allow (the refused stand-in
that ends an episode at an expert action no candidate expresses, which only a non-move
action can be now: moves are projected to the nearest allowed one) are dropped.

:func:`train_bc_run` trains on them with BC's loop (:func:`training.learners.bc.fit`,
a checkpoint after every epoch, so that an interrupted run resumes where it stopped and
ends with the same weights as an uninterrupted one) into a run folder
(:mod:`training.learners.runs`). :func:`load_network_policy` loads the run folders of
the BC network (every built-in kind: the ``load`` of their learners).
"""

from __future__ import annotations

import os
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

from fetchcarry_env.errors import InputError
from fetchcarry_env.jsontext import describe
from fetchcarry_env.observation import Capacity, observation_size
from fetchcarry_env.phases import PhaseLayout
from training.envs import env_id_of
from training.learners import runs
from training.learners.bc import CHECKPOINT_FIELDS, BCConfig, BCPolicy, Demonstrations, fit
from training.learners.encoders import Ensemble, build_network, network_input
from training.policies.phase_expert import MASK_INFO


def demonstrations_from_dataset(
    dataset_id: str, episodes: int | None = None, obs_mode: str = "state"
) -> tuple[Demonstrations, Capacity]:
    """The labelled states of a phases dataset (its first ``episodes``, or all) and the capacity of its env.

    Each state is what a network of ``obs_mode`` reads (:func:`~training.learners.encoders.network_input`:
    the state vector as float32, or the images flattened, uint8). Raises :class:`InputError`
    (bad input) when the dataset was not recorded in the candidate-phase interface, or
    holds no images of ``obs_mode``.
    """
    from training.data.datasets import load, make_recorded_env

    dataset = load(dataset_id)
    if episodes is not None and not 1 <= episodes <= dataset.total_episodes:
        raise InputError(f"dataset {dataset_id!r} has {dataset.total_episodes} episodes, not the first {episodes}")
    env = make_recorded_env(dataset, dataset_id)
    try:
        if env.spec is None or env.spec.id != env_id_of(runs.INTERFACE):
            raise InputError(
                f"dataset {dataset_id!r} was recorded in {env.spec.id if env.spec else '?'}, "
                f"not {env_id_of(runs.INTERFACE)}: "
                "make one with fetchcarry generate ... --interface phases"
            )
        capacity = env.unwrapped.capacity
        size = env.action_space.n
    finally:
        env.close()
    observations, masks, labels = [], [], []
    chosen = None if episodes is None else list(range(episodes))
    episodes = steps = dropped = successes = 0
    for episode in dataset.iterate_episodes(chosen):
        if MASK_INFO not in episode.infos:
            raise InputError(f"dataset {dataset_id!r} stores no candidate masks (per-step info {MASK_INFO!r})")
        mask = np.asarray(episode.infos[MASK_INFO], dtype=bool)[:-1]
        actions = np.asarray(episode.actions, dtype=np.int64).reshape(-1)
        allowed = mask[np.arange(len(actions)), actions]
        try:
            states = network_input(episode.observations, obs_mode)[:-1][allowed]
        except KeyError:
            raise InputError(
                f"dataset {dataset_id!r} holds no {obs_mode} observations: make a copy that does with "
                f"fetchcarry dataset render {dataset_id} --obs-mode {obs_mode} --out NEW_ID"
            ) from None
        observations.append(states)
        masks.append(mask[allowed])
        labels.append(actions[allowed])
        episodes += 1
        steps += len(actions)
        dropped += int((~allowed).sum())
        successes += bool(episode.terminations[-1])
    demonstrations = Demonstrations(
        np.concatenate(observations) if observations else np.zeros((0, 1), np.float32),
        np.concatenate(masks) if masks else np.zeros((0, size), bool),
        np.concatenate(labels) if labels else np.zeros(0, np.int64),
        {"dataset_id": dataset_id, "episodes": episodes, "steps": steps, "labelled": steps - dropped,
         "dropped": dropped, "terminated": successes},
    )  # fmt: skip
    demonstrations.stats["observation"] = runs.observation_of(obs_mode, dict(env.spec.kwargs))  # the images' options
    return demonstrations, capacity


def train_bc_run(
    dataset: str,
    config: BCConfig,
    out: str | Path,
    *,
    resume: bool = False,
    progress: bool = True,
    episodes: int | None = None,
) -> BCPolicy:
    """Behaviour cloning on the phases dataset ``dataset`` (its first ``episodes``, or all) into ``out``.

    Resumable: an interrupted run continues from its last epoch; a complete one is loaded.
    The ``train`` of the ``bc`` learner (:mod:`training.learners.registry`: the fields of
    :class:`~training.learners.options.BCRun` as keyword arguments).
    """
    demonstrations, capacity = demonstrations_from_dataset(dataset, episodes, config.obs_mode)
    options = {"dataset": dataset, **({} if episodes is None else {"episodes": episodes}), **asdict(config)}
    candidates, features = demonstrations.masks.shape[1], demonstrations.observations.shape[1]
    observation = demonstrations.stats.pop("observation")
    config_json = runs.run_config("bc", options, config, capacity, candidates, features, demonstrations.stats,
                                  observation=observation if config.obs_mode != "state" else None)  # fmt: skip
    folder, checkpoint = runs.start_run(out, config_json, resume=resume)
    if runs.read_config(folder).get("complete"):
        return runs.load_policy(folder)
    done = 0
    if checkpoint is not None:  # an empty one too: it lacks every field
        runs.check_checkpoint_fields(folder / runs.CHECKPOINT_FILE, checkpoint, CHECKPOINT_FIELDS)
        done = runs.checkpoint_counter(folder, checkpoint, "epoch", config.epochs)
    with tqdm(total=config.epochs, initial=done, desc=f"bc {folder.name}", unit="epoch", disable=not progress) as bar:

        def on_epoch(row: dict[str, Any]) -> None:
            runs.write_metrics(folder, [*saved_rows, row])
            saved_rows.append(row)
            bar.update(1)
            bar.set_postfix_str(f"loss {row['loss']:.3f} accuracy {row['accuracy']:.1%}", refresh=False)

        saved_rows: list[dict[str, Any]] = [dict(r) for r in checkpoint["metrics"]] if checkpoint is not None else []
        network, _ = fit(
            demonstrations,
            config,
            capacity,
            checkpoint=checkpoint,
            save=lambda state: runs.save_checkpoint(folder, state),
            on_epoch=on_epoch,
            checkpoint_file=folder / runs.CHECKPOINT_FILE,
        )
    runs.finish_run(folder, network, config_json)
    return BCPolicy(network, config, capacity)


def load_network_policy(path: str | Path, env: Any = None) -> Any:
    """The :class:`BCPolicy` of a ``bc``, ``dagger``, ``ppo`` or ``ensemble`` run folder (their ``load``).

    Reads ``config.json`` (checked: :func:`training.learners.runs.read_config`) and the
    ``model.pt`` tensors (``weights_only``); :class:`~training.learners.runs.RunFolderError` otherwise.
    With ``env``, the policy acts at the env's observation capacity (:func:`acting_capacity`).
    """
    path = Path(path)
    saved = runs.read_config(path)
    config = runs.network_config(saved)
    trained = Capacity(**saved["capacity"])
    ensemble = saved["kind"] == "ensemble"
    configs = [runs.network_config(member) for member in saved["options"]["members"]] if ensemble else [config]
    capacity = acting_capacity(path, trained, configs, env)
    candidates, features = saved["candidates"], saved["features"]
    if capacity != trained:
        candidates, features = PhaseLayout.for_postures(capacity=capacity).size, observation_size(capacity)
    try:
        built = [build_network(c, capacity, candidates, torch.zeros(1, features)) for c in configs]
    except ValueError as error:  # e.g. the set encoder for another number of candidates than its layout's
        raise runs.RunFolderError(f"{path / runs.CONFIG_FILE}: {error}") from None
    network = Ensemble(built) if ensemble else built[0]
    weights = path / runs.WEIGHTS_FILE
    if not os.path.lexists(weights):
        raise runs.RunFolderError(f"{path} has no {runs.WEIGHTS_FILE} (an unfinished run: resume it first)")
    load_weights(network, weights)
    policy = BCPolicy(network, config, capacity, env)
    with torch.inference_mode():
        # Trace it now, so that the first decision is not slower.
        policy.candidate_scores(torch.zeros(1, features), torch.arange(candidates))
    return policy


def acting_capacity(path: Path, trained: Capacity, configs: list[BCConfig], env: Any) -> Capacity:
    """The capacity a run's policy acts at: ``env``'s, if it has one, else the one it was trained with.

    The set encoder's weights do not depend on the capacity (one token per slot, one head per
    kind of slot), so it acts at any capacity; a flat network (``mlp``) has one input per
    feature and one output per candidate of the capacity it was trained with, and refuses
    any other with :class:`CapacityMismatch`.
    """
    capacity = trained
    if env is not None:
        try:
            capacity = env.get_wrapper_attr("capacity")
        except AttributeError:
            capacity = trained
    if capacity == trained or all(c.encoder == "set" for c in configs):
        return capacity
    raise CapacityMismatch(
        f"{path} is a flat network ({configs[0].encoder}) trained at capacity {asdict(trained)}; the env has "
        f"{asdict(capacity)}, and a flat network acts only at its own capacity (one input per feature, one "
        f"output per candidate): make the env with capacity={asdict(trained)} (--capacity on the command "
        "line), or train a set encoder (--encoder set), which acts at any capacity"
    )


class CapacityMismatch(InputError):
    """A flat network asked to act at another observation capacity than the one it was trained with."""


def load_weights(network: torch.nn.Module, weights: Path) -> dict[str, torch.Tensor]:
    """Load ``weights`` (a run's ``model.pt``) into ``network`` and return its tensors; :class:`RunFolderError` else.

    The file must be a regular file of at most twice the network's own size (plus 1 MB)
    holding exactly its tensors (names and shapes); every weight must be a finite number
    once loaded (a NaN or an infinity, or a float64 beyond float32's range, is refused).
    """
    size = sum(t.numel() * t.element_size() for t in network.state_dict().values())
    state = runs.read_tensors(weights, 2 * size + 2**20)
    named = isinstance(state, dict) and all(isinstance(k, str) and torch.is_tensor(v) for k, v in state.items())
    if not named:
        raise runs.RunFolderError(f"{weights} does not hold a network's weights (named tensors)")
    expected = network.state_dict()
    missing, unexpected = sorted(set(expected) - set(state)), sorted(set(state) - set(expected))
    if missing or unexpected:
        names = ", ".join(describe(name) for name in (missing or unexpected)[:3])
        counts = f"{len(missing)} tensors missing, {len(unexpected)} unexpected ({names} ...)"
        raise runs.RunFolderError(f"{weights} does not fit the network its config.json describes: {counts}")
    try:
        network.load_state_dict(state)
    except (RuntimeError, KeyError, TypeError, ValueError) as error:
        first = (str(error).splitlines() or [""])[0][:300]
        raise runs.RunFolderError(f"{weights} does not fit the network its config.json describes: {first}") from None
    runs.check_finite(weights, dict(network.state_dict()))
    return state
