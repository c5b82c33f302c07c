"""Run folders of trained policies (``bc``, ``dagger``, ``ppo``, ``ensemble``, ...): what they hold, and loading them.

A run folder holds

- ``config.json``: ``kind`` (``bc``, ``dagger``, ``ppo``, ``ensemble`` or another registered
  learner's, :mod:`training.learners.registry`), ``interface`` (``phases``:
  the policy acts in ``FetchCarryPushPhases-v0``'s candidate phases), ``env_id``,
  ``options`` (every option of the run, as given), ``config`` (the network:
  :class:`~training.learners.bc.BCConfig`), ``capacity`` (the observation's slots),
  ``candidates`` (K) and ``features`` (the observation vector's length), ``data``
  (what it was trained on) and ``complete`` (whether the run finished);
- ``metrics.csv``: one row per epoch (bc), iteration (dagger) or rollout (ppo);
- ``checkpoint.pt``: the training state to resume from (weights, optimiser, counters);
- ``model.pt``: the policy's weights (a scorer of candidates, :mod:`training.learners.encoders`).

:func:`load_policy` loads a run folder through the learner its ``kind`` names. Every
built-in kind acts through the same network (a PPO run's actor is a BC network, so a BC
run of the same encoder initialises it), so
:func:`training.learners.imitation.load_network_policy` builds one
:class:`~training.learners.bc.BCPolicy` for all of them; an ``ensemble``
(:mod:`training.learners.ensemble`) holds several such networks, each member's settings
in ``options.members``, and acts on the mean of their log-probabilities. Loading reads JSON and
``torch.load(..., weights_only=True)`` tensors only: nothing in a run folder runs code.
A ``config.json`` with an unknown key, a missing key, a bad kind or a value of the
wrong type is a :class:`RunFolderError` (the user's bad input).
"""

from __future__ import annotations

import csv
import json
import math
import os
import tempfile
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

import torch

from fetchcarry_env.errors import InputError
from fetchcarry_env.observation import Capacity
from training.learners import registry
from training.learners.options import BCConfig

CONFIG_FILE, METRICS_FILE, WEIGHTS_FILE, CHECKPOINT_FILE = "config.json", "metrics.csv", "model.pt", "checkpoint.pt"
INTERFACE = "phases"
ENV_ID = "FetchCarryPushPhases-v0"
REQUIRED_KEYS = ("kind", "config", "capacity", "candidates", "features")
OPTIONAL_KEYS = ("interface", "env_id", "options", "data", "complete")


class RunFolderError(InputError):
    """A folder that is not a loadable run folder (bad or missing ``config.json``, weights that do not fit)."""


def network_kinds() -> tuple[str, ...]:
    """The registered kinds whose runs act through the BC network (``bc``, ``dagger``, ``ppo``, ``ensemble``)."""
    return tuple(learner.kind for learner in registry.learners() if learner.load == registry.NETWORK_LOADER)


def read_saved(path: str | Path) -> dict[str, Any]:
    """The JSON object in run folder ``path``'s ``config.json`` (any kind, unchecked); :class:`RunFolderError` else."""
    file = Path(path) / CONFIG_FILE
    try:
        saved = json.loads(file.read_text())
    except FileNotFoundError:
        raise RunFolderError(f"{path} is not a run folder: no {CONFIG_FILE}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise RunFolderError(f"{file} is not valid JSON: {error}") from None
    if not isinstance(saved, dict):
        raise RunFolderError(f"{file} does not hold a run's configuration (a JSON object)")
    return saved


def read_config(path: str | Path) -> dict[str, Any]:
    """The checked ``config.json`` of a run folder of the BC network; :class:`RunFolderError` otherwise."""
    file = Path(path) / CONFIG_FILE
    saved = read_saved(path)
    unknown = sorted(set(saved) - set(REQUIRED_KEYS) - set(OPTIONAL_KEYS))
    if unknown:
        raise RunFolderError(f"{file}: unknown keys {', '.join(unknown)}")
    missing = [key for key in REQUIRED_KEYS if key not in saved]
    if missing:
        raise RunFolderError(f"{file}: missing keys {', '.join(missing)}")
    kinds = network_kinds()
    if saved["kind"] not in kinds:
        raise RunFolderError(f"{file}: kind must be one of {', '.join(kinds)}, got {saved['kind']!r}")
    if saved.get("interface", INTERFACE) != INTERFACE:
        raise RunFolderError(f"{file}: interface must be {INTERFACE!r}, got {saved['interface']!r}")
    _check_fields(file, "config", saved["config"], BCConfig)
    if saved["kind"] == "ensemble":
        options = saved.get("options")
        members = options.get("members") if isinstance(options, dict) else None
        if not isinstance(members, list) or len(members) < 2 or not all(isinstance(m, dict) for m in members):
            raise RunFolderError(f"{file}: options.members must list at least two members (JSON objects)")
        for k, member in enumerate(members):
            _check_fields(file, f"options.members[{k}].config", member.get("config"), BCConfig)
    _check_fields(file, "capacity", saved["capacity"], Capacity)
    for key in ("candidates", "features"):
        if not isinstance(saved[key], int) or isinstance(saved[key], bool) or saved[key] < 1:
            raise RunFolderError(f"{file}: {key} must be a positive integer, got {saved[key]!r}")
    return saved


def _check_fields(file: Path, key: str, value: Any, cls: type) -> None:
    if not isinstance(value, dict):
        raise RunFolderError(f"{file}: {key} must be a JSON object")
    known = {f.name: f for f in fields(cls)}
    unknown = sorted(set(value) - set(known))
    if unknown:
        raise RunFolderError(f"{file}: unknown keys in {key}: {', '.join(unknown)}")
    for name, item in value.items():
        expected = type(getattr(cls(), name))
        plain = isinstance(item, expected) or (expected is float and isinstance(item, int))
        if not plain or isinstance(item, bool) != (expected is bool):
            raise RunFolderError(f"{file}: {key}.{name} must be a {expected.__name__}, got {item!r}")


LEGACY_CONFIG: dict[str, Any] = {"relative": False, "push_scores": False, "avoid_repeats": False,
                                 "avoid_returns": False, "push_after_approach": False}  # fmt: skip
"""BCConfig fields added after run folders were first written: a config without them meant these values."""


def network_config(saved: dict[str, Any]) -> Any:
    """The :class:`BCConfig` of a checked config (its own checks raise :class:`InputError`).

    A field missing from an older run folder takes the value it had before the field
    existed (:data:`LEGACY_CONFIG`), so old runs load and act as they did.
    """
    return BCConfig(**{**LEGACY_CONFIG, **saved["config"]})


def load_policy(path: str | Path, env: Any = None) -> Any:
    """The policy of a run folder of any registered kind, behind stable-baselines3's ``predict`` protocol.

    ``config.json``'s ``kind`` names the learner (:mod:`training.learners.registry`) whose
    ``load(path, env)`` loads it; the built-in kinds load with
    :func:`training.learners.imitation.load_network_policy`. ``env`` (a
    ``FetchCarryPushPhases-v0`` env) lets ``predict`` ask it for the masks when none are
    given. Raises :class:`RunFolderError` (bad input) for anything that is not a loadable run folder.
    """
    kind = read_saved(path).get("kind")
    if not (isinstance(kind, str) and kind in registry.kinds()):
        read_config(path)  # raises: it says what is wrong (unknown or missing keys, the kind)
    return registry.loader(kind)(Path(path), env)


# ---------------------------------------------------------------------------- writing
def write_config(out: Path, config: dict[str, Any]) -> None:
    """Write ``config.json`` atomically."""
    out.mkdir(parents=True, exist_ok=True)
    atomic_write(out / CONFIG_FILE, (json.dumps(config, indent=2) + "\n").encode())


def write_metrics(out: Path, rows: list[dict[str, Any]]) -> None:
    """Write ``metrics.csv`` (all rows, atomically; the columns of the first row)."""
    if not rows:
        return
    handle, temporary = tempfile.mkstemp(dir=out, prefix=".metrics_", suffix=".tmp")
    with os.fdopen(handle, "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    os.replace(temporary, out / METRICS_FILE)


def read_metrics(path: str | Path) -> list[dict[str, float]]:
    """The rows of a run's ``metrics.csv``, as numbers."""
    with open(Path(path) / METRICS_FILE, newline="") as file:
        return [{k: _number(v) for k, v in row.items()} for row in csv.DictReader(file)]


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return math.nan


def save_checkpoint(out: Path, state: dict[str, Any]) -> None:
    """Write ``checkpoint.pt`` atomically (tensors, numbers, strings and lists of them only)."""
    handle, temporary = tempfile.mkstemp(dir=out, prefix=".checkpoint_", suffix=".tmp")
    os.close(handle)
    try:
        torch.save(state, temporary)
        os.replace(temporary, out / CHECKPOINT_FILE)
    finally:
        Path(temporary).unlink(missing_ok=True)


def load_checkpoint(out: Path) -> dict[str, Any] | None:
    """The state in ``checkpoint.pt``, or None if there is none (``weights_only``: it runs no code)."""
    file = out / CHECKPOINT_FILE
    if not file.is_file():
        return None
    try:
        return torch.load(file, weights_only=True, map_location="cpu")
    except (RuntimeError, EOFError, OSError, ValueError) as error:
        raise RunFolderError(f"{file} cannot be read: {error}") from None


def save_weights(out: Path, network: torch.nn.Module) -> None:
    handle, temporary = tempfile.mkstemp(dir=out, prefix=".model_", suffix=".tmp")
    os.close(handle)
    try:
        torch.save(network.state_dict(), temporary)
        os.replace(temporary, out / WEIGHTS_FILE)
    finally:
        Path(temporary).unlink(missing_ok=True)


def atomic_write(path: Path, data: bytes) -> None:
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}_", suffix=".tmp")
    with os.fdopen(handle, "wb") as file:
        file.write(data)
    os.replace(temporary, path)


def start_run(out: str | Path, config: dict[str, Any], *, resume: bool) -> tuple[Path, dict[str, Any] | None]:
    """Prepare run folder ``out`` for ``config``; return it and the checkpoint to resume from (or None).

    Without ``resume`` the folder must not hold a run already (``FileExistsError`` is
    not used: a :class:`RunFolderError` says what to do). With ``resume`` the folder's
    ``config.json`` must describe the same run (its ``options`` equal), and a complete
    run is not trained again.
    """
    out = Path(out)
    if (out / CONFIG_FILE).exists():
        if not resume:
            raise RunFolderError(f"{out} already holds a run: resume it, or choose another folder")
        saved = read_saved(out)
        if saved.get("kind") != config["kind"] or saved.get("options") != config["options"]:
            raise RunFolderError(f"{out} holds a run with other options: resume it with the same options")
        return out, load_checkpoint(out)
    if out.exists() and any(out.iterdir()):
        raise RunFolderError(f"{out} exists and is not an empty folder or a run folder")
    write_config(out, {**config, "complete": False})
    return out, None


def run_config(kind: str, options: dict[str, Any], config: Any, capacity: Capacity,
               candidates: int, features: int, data: dict[str, Any]) -> dict[str, Any]:  # fmt: skip
    """The ``config.json`` of a run (see above)."""
    return {
        "kind": kind,
        "interface": INTERFACE,
        "env_id": ENV_ID,
        "options": options,
        "config": asdict(config),
        "capacity": asdict(capacity),
        "candidates": candidates,
        "features": features,
        "data": data,
    }


def finish_run(folder: Path, network: torch.nn.Module, config_json: dict[str, Any]) -> None:
    """Write the final weights and mark the run complete."""
    save_weights(folder, network)
    write_config(folder, {**config_json, "complete": True})
