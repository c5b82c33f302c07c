"""Behaviour cloning into a run folder: demonstrations from a Minari dataset, resumable epochs.

:func:`demonstrations_from_dataset` reads a dataset recorded in the candidate-phase
interface (``fetchcarry generate --interface phases``): its actions are candidate
indices and its per-step info ``action_mask`` holds each state's mask, so nothing but
the dataset is needed. Steps whose action the mask does not allow (the refused stand-in
that ends an episode at an unexpressible expert action) are dropped.

:func:`fit` is BC's training loop (:func:`training.baselines.bc.train_bc`'s loss:
cross-entropy over the allowed candidates) with a checkpoint after every epoch, so
that an interrupted run resumes where it stopped and ends with the same weights as an
uninterrupted one. :func:`train_bc_run` puts the two together into a run folder
(:mod:`training.baselines.runs`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from fetchcarry_env.observation import Capacity
from training.baselines import runs
from training.baselines.bc import BCConfig, BCPolicy, Demonstrations
from training.baselines.encoders import build_network
from training.phase_recording import MASK_INFO


def demonstrations_from_dataset(dataset_id: str) -> tuple[Demonstrations, Capacity]:
    """The labelled states of a phases dataset and the observation capacity of its env.

    Raises ``UsageError`` (a ``ValueError``-like bad input) when the dataset was not
    recorded in the candidate-phase interface.
    """
    from fetchcarry_env.errors import UsageError
    from training.datasets import load, make_recorded_env

    dataset = load(dataset_id)
    env = make_recorded_env(dataset, dataset_id)
    try:
        if env.spec is None or env.spec.id != runs.ENV_ID:
            raise UsageError(
                f"dataset {dataset_id!r} was recorded in {env.spec.id if env.spec else '?'}, not {runs.ENV_ID}: "
                "make one with fetchcarry generate ... --interface phases"
            )
        capacity = env.unwrapped.capacity
        size = env.action_space.n
    finally:
        env.close()
    observations, masks, labels = [], [], []
    episodes = steps = dropped = successes = 0
    for episode in dataset.iterate_episodes():
        if MASK_INFO not in episode.infos:
            raise UsageError(f"dataset {dataset_id!r} stores no candidate masks (per-step info {MASK_INFO!r})")
        mask = np.asarray(episode.infos[MASK_INFO], dtype=bool)[:-1]
        actions = np.asarray(episode.actions, dtype=np.int64).reshape(-1)
        allowed = mask[np.arange(len(actions)), actions]
        observations.append(np.asarray(episode.observations["observation"], dtype=np.float32)[:-1][allowed])
        masks.append(mask[allowed])
        labels.append(actions[allowed])
        episodes += 1
        steps += len(actions)
        dropped += int((~allowed).sum())
        successes += bool(episode.terminations[-1])
    demonstrations = Demonstrations(
        np.concatenate(observations).astype(np.float32) if observations else np.zeros((0, 1), np.float32),
        np.concatenate(masks) if masks else np.zeros((0, size), bool),
        np.concatenate(labels) if labels else np.zeros(0, np.int64),
        {"dataset_id": dataset_id, "episodes": episodes, "steps": steps, "labelled": steps - dropped,
         "dropped": dropped, "terminated": successes},
    )  # fmt: skip
    return demonstrations, capacity


def fit(
    demonstrations: Demonstrations,
    config: BCConfig,
    capacity: Capacity,
    *,
    checkpoint: dict[str, Any] | None = None,
    save: Callable[[dict[str, Any]], None] | None = None,
    on_epoch: Callable[[dict[str, Any]], None] | None = None,
) -> tuple[nn.Module, list[dict[str, Any]]]:
    """Train a fresh network for ``config.epochs`` epochs; return it and one metrics row per epoch.

    ``checkpoint`` (what ``save`` was last given) resumes training after its epoch;
    ``save`` is called with the training state after every epoch. Deterministic on CPU
    for one ``config.seed``, interrupted or not.
    """
    if len(demonstrations) == 0:
        raise ValueError("no labelled demonstrations to learn from")
    torch.set_num_threads(1)  # faster here than two threads, and the same sums every run
    torch.manual_seed(config.seed)
    observations = torch.as_tensor(demonstrations.observations)
    masks = torch.as_tensor(demonstrations.masks)
    labels = torch.as_tensor(demonstrations.labels)
    network = build_network(config, capacity, masks.shape[1], observations)
    optimiser = torch.optim.Adam(network.parameters(), lr=config.learning_rate, weight_decay=config.weight_decay)
    order = torch.Generator().manual_seed(config.seed)
    metrics: list[dict[str, Any]] = []
    first = 0
    elapsed = 0.0
    if checkpoint is not None:
        network.load_state_dict(checkpoint["network"])
        optimiser.load_state_dict(checkpoint["optimiser"])
        order.set_state(checkpoint["order"])
        metrics = [dict(row) for row in checkpoint["metrics"]]
        first = int(checkpoint["epoch"])
        elapsed = float(metrics[-1]["seconds"]) if metrics else 0.0
    start = time.perf_counter() - elapsed
    for epoch in range(first, config.epochs):
        network.train()
        total = correct = 0
        loss_sum = 0.0
        for batch in torch.randperm(len(labels), generator=order).split(config.batch_size):
            logits = network(observations[batch]).masked_fill(~masks[batch], -1e9)
            loss = nn.functional.cross_entropy(logits, labels[batch])
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            loss_sum += loss.item() * len(batch)
            correct += int((logits.argmax(dim=1) == labels[batch]).sum())
            total += len(batch)
        row = {"epoch": epoch + 1, "loss": loss_sum / total, "accuracy": correct / total,
               "seconds": time.perf_counter() - start}  # fmt: skip
        metrics.append(row)
        if save is not None:
            save({"network": network.state_dict(), "optimiser": optimiser.state_dict(), "order": order.get_state(),
                  "metrics": metrics, "epoch": epoch + 1})  # fmt: skip
        if on_epoch is not None:
            on_epoch(row)
    return network.eval(), metrics


def run_config(kind: str, options: dict[str, Any], config: BCConfig, capacity: Capacity,
               candidates: int, features: int, data: dict[str, Any]) -> dict[str, Any]:  # fmt: skip
    """The ``config.json`` of a run (see :mod:`training.baselines.runs`)."""
    return {
        "kind": kind,
        "interface": runs.INTERFACE,
        "env_id": runs.ENV_ID,
        "options": options,
        "config": asdict(config),
        "capacity": asdict(capacity),
        "candidates": candidates,
        "features": features,
        "data": data,
    }


def train_bc_run(
    dataset_id: str,
    config: BCConfig,
    out: str | Path,
    *,
    resume: bool = False,
    progress: bool = True,
) -> BCPolicy:
    """Behaviour cloning on the phases dataset ``dataset_id`` into the run folder ``out`` (resumable)."""
    from tqdm import tqdm

    demonstrations, capacity = demonstrations_from_dataset(dataset_id)
    options = {"dataset": dataset_id, **asdict(config)}
    candidates, features = demonstrations.masks.shape[1], demonstrations.observations.shape[1]
    config_json = run_config("bc", options, config, capacity, candidates, features, demonstrations.stats)
    folder, checkpoint = runs.start_run(out, config_json, resume=resume)
    if runs.read_config(folder).get("complete"):
        return runs.load_policy(folder)
    done = int(checkpoint["epoch"]) if checkpoint else 0
    with tqdm(total=config.epochs, initial=done, desc=f"bc {folder.name}", unit="epoch", disable=not progress) as bar:

        def on_epoch(row: dict[str, Any]) -> None:
            runs.write_metrics(folder, [*saved_rows, row])
            saved_rows.append(row)
            bar.update(1)
            bar.set_postfix_str(f"loss {row['loss']:.3f} accuracy {row['accuracy']:.1%}", refresh=False)

        saved_rows: list[dict[str, Any]] = [dict(r) for r in checkpoint["metrics"]] if checkpoint else []
        network, _ = fit(
            demonstrations,
            config,
            capacity,
            checkpoint=checkpoint,
            save=lambda state: runs.save_checkpoint(folder, state),
            on_epoch=on_epoch,
        )
    finish(folder, network, config_json)
    return BCPolicy(network, config, capacity)


def finish(folder: Path, network: nn.Module, config_json: dict[str, Any]) -> None:
    """Write the final weights and mark the run complete."""
    runs.save_weights(folder, network)
    runs.write_config(folder, {**config_json, "complete": True})
