"""Run folders of trained policies (``bc``, ``dagger``, ``ppo``, ``ensemble``, ...): what they hold, and loading them.

A run folder holds

- ``config.json``: ``kind`` (``bc``, ``dagger``, ``ppo``, ``ensemble`` or another registered
  learner's, :mod:`training.learners.registry`), ``interface`` (``phases``:
  the policy acts in ``FetchCarryPushPhases-v0``'s candidate phases), ``env_id``,
  ``options`` (every option of the run, as given), ``config`` (the network:
  :class:`~training.learners.bc.BCConfig`), ``capacity`` (the observation's slots),
  ``candidates`` (K) and ``features`` (the length of the network's input row: the
  observation vector, or the images flattened), ``observation`` (the env's observation
  keywords the network was trained in: ``obs_mode`` and, for ``topdown`` or ``rgbd``, the
  image options, e.g. ``{"obs_mode": "topdown", "topdown_size": 64, "topdown_frame":
  "world"}``; the env a loaded run acts in is made with them), ``data``
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

A run folder is data a stranger may have written, so what it says is bounded before
anything acts on it: ``config.json`` is read as a regular file of at most
:data:`MAX_CONFIG_BYTES` (:func:`fetchcarry_env.jsontext.read_json`: no FIFO, device or
deep nesting); its capacity within the scenario format's counts
(:data:`fetchcarry_env.scenario.MAX_COUNTS`, :data:`MAX_POSTURES`), its ``features``
the observation's length for that capacity, its network within :data:`MAX_HIDDEN`
units, :data:`MAX_CANDIDATES` scores and :data:`MAX_PARAMETERS` weights. ``model.pt``
and ``checkpoint.pt`` are read as regular files of bounded size (:func:`read_tensors`);
weights that are not finite (NaN, infinities) or not dense are refused, on load and on
resume, and a checkpoint's counter must lie within the run's budget
(:func:`checkpoint_counter`). A resumed checkpoint holds exactly its learner's fields
(:func:`check_checkpoint_fields`), each checked against what it is loaded into before
it is: a network's tensors (:func:`check_module_state`), an Adam optimiser's state
(:func:`check_adam_state`), a random generator's (:func:`check_generator_state`) and the
metrics rows (:func:`check_metric_rows`). Every refusal is a :class:`RunFolderError`
naming the file (and the field).
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import pickle
import stat
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

import torch

from fetchcarry_env.errors import InputError
from fetchcarry_env.jsontext import JsonInputError, describe, read_json
from fetchcarry_env.observation import Capacity, observation_size
from fetchcarry_env.observations.modes import get_mode
from fetchcarry_env.scenario import MAX_COUNTS
from training.envs import env_id_of
from training.files import atomic_file, write_atomically
from training.learners import registry
from training.learners.encoders import image_shape
from training.learners.options import BCConfig

CONFIG_FILE, METRICS_FILE, WEIGHTS_FILE, CHECKPOINT_FILE = "config.json", "metrics.csv", "model.pt", "checkpoint.pt"
INTERFACE = "phases"  # every learner acts in the candidate phases (FetchCarryPushPhases-v0)
REQUIRED_KEYS = ("kind", "config", "capacity", "candidates", "features")
OPTIONAL_KEYS = ("interface", "env_id", "options", "data", "complete", "observation")

MAX_CONFIG_BYTES = 4 * 2**20  # a config.json is a few kB (an ensemble's some 10 kB)
MAX_POSTURES = 64  # a capacity's posture slots (the env's default has 4)
MAX_HIDDEN = 4096  # units per hidden layer (the published runs have 256)
MAX_CANDIDATES = 2**18  # scores (4,080 by default; 130,560 at the scenario format's largest counts)
MAX_PARAMETERS = 100_000_000  # weights of one run's networks (400 MB; a published flat MLP has 1.2 million)
MAX_MEMBERS = 64  # runs in an ensemble
MAX_CHECKPOINT_BYTES = 4 * 2**30  # a checkpoint.pt (a DAgger run's holds its labelled states)
SEEDS = (-(2**63), 2**64 - 1)  # the seeds torch.Generator.manual_seed takes


class RunFolderError(InputError):
    """A folder that is not a loadable run folder (bad or missing ``config.json``, weights that do not fit)."""


def network_kinds() -> tuple[str, ...]:
    """The registered kinds whose runs act through the BC network (``bc``, ``dagger``, ``ppo``, ``ensemble``)."""
    return tuple(learner.kind for learner in registry.learners() if learner.load == registry.NETWORK_LOADER)


def read_saved(path: str | Path) -> dict[str, Any]:
    """The JSON object in run folder ``path``'s ``config.json`` (any kind, unchecked); :class:`RunFolderError` else."""
    file = Path(path) / CONFIG_FILE
    try:
        saved = read_json(file, MAX_CONFIG_BYTES)
    except FileNotFoundError:
        raise RunFolderError(f"{path} is not a run folder: no {CONFIG_FILE}") from None
    except JsonInputError as error:
        raise RunFolderError(f"{file}: {error}") from None
    except OSError as error:
        raise RunFolderError(f"{file} cannot be read: {error.strerror or error}") from None
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
    configs = {"config": saved["config"]}
    if saved["kind"] == "ensemble":
        options = saved.get("options")
        members = options.get("members") if isinstance(options, dict) else None
        if not isinstance(members, list) or len(members) < 2 or not all(isinstance(m, dict) for m in members):
            raise RunFolderError(f"{file}: options.members must list at least two members (JSON objects)")
        if len(members) > MAX_MEMBERS:
            raise RunFolderError(f"{file}: options.members lists {len(members):,} runs, more than {MAX_MEMBERS}")
        configs.update({f"options.members[{k}].config": member.get("config") for k, member in enumerate(members)})
    for key, config in configs.items():
        _check_fields(file, key, config, BCConfig)
        _check_network_config(file, key, config)
    _check_fields(file, "capacity", saved["capacity"], Capacity)
    _check_capacity(file, saved["capacity"])
    for key in ("candidates", "features"):
        if not isinstance(saved[key], int) or isinstance(saved[key], bool) or saved[key] < 1:
            raise RunFolderError(f"{file}: {key} must be a positive integer, got {describe(saved[key])}")
    if saved["candidates"] > MAX_CANDIDATES:
        raise RunFolderError(f"{file}: candidates {saved['candidates']:,} is more than the {MAX_CANDIDATES:,} "
                             "a run's network may score")  # fmt: skip
    obs_mode = saved["config"].get("obs_mode", "state")
    if obs_mode == "state":
        size = observation_size(Capacity(**saved["capacity"]))
        if saved["features"] != size:
            raise RunFolderError(f"{file}: features must be the observation's length for its capacity ({size}), "
                                 f"got {saved['features']:,}")  # fmt: skip
    else:
        try:
            image_shape(obs_mode, saved["features"])
        except ValueError as error:
            raise RunFolderError(f"{file}: features: {error}") from None
    if "observation" in saved:
        _check_observation(file, saved)
    weights = sum(network_parameters(saved, config) for config in configs.values())
    if weights > MAX_PARAMETERS:
        raise RunFolderError(f"{file}: its networks would hold {weights:,} weights, more than {MAX_PARAMETERS:,}")
    return saved


def _check_observation(file: Path, saved: dict[str, Any]) -> None:
    """``observation``: a JSON object of the network's ``obs_mode`` and that mode's image options (in range)."""
    observation = saved["observation"]
    name = saved["config"].get("obs_mode", "state")
    if not isinstance(observation, dict) or observation.get("obs_mode") != name:
        raise RunFolderError(f"{file}: observation must be a JSON object whose obs_mode is the network's ({name!r})")
    mode = get_mode(name)  # the config's check has refused an unknown mode
    try:
        mode.resolved({key: value for key, value in observation.items() if key != "obs_mode"})
    except ValueError as error:
        raise RunFolderError(f"{file}: observation: {error}") from None
    side = observation.get(mode.side_option) if mode.side_option else None
    if side is not None and image_shape(name, saved["features"])[1] != side:
        raise RunFolderError(f"{file}: observation: images of {side} pixels a side are not the network's input")


def _check_network_config(file: Path, key: str, config: dict[str, Any]) -> None:
    """Bounds on a (type-checked) network config: hidden units, the seed, finite numbers, BCConfig's own checks."""
    hidden, seed = config.get("hidden", 1), config.get("seed", 0)
    if not 1 <= hidden <= MAX_HIDDEN:
        raise RunFolderError(f"{file}: {key}.hidden must be from 1 to {MAX_HIDDEN}, got {describe(hidden)}")
    if not SEEDS[0] <= seed <= SEEDS[1]:
        raise RunFolderError(f"{file}: {key}.seed {describe(seed)} is out of range")
    for name, value in config.items():
        if isinstance(value, float) and not math.isfinite(value):
            raise RunFolderError(f"{file}: {key}.{name} must be a finite number, got {value!r}")
    try:
        BCConfig(**{**LEGACY_CONFIG, **config})
    except InputError as error:
        raise RunFolderError(f"{file}: {key}: {error}") from None


def _check_capacity(file: Path, capacity: dict[str, int]) -> None:
    """Each of a (type-checked) capacity's counts within what a scenario may hold."""
    highs = {**MAX_COUNTS, "postures": MAX_POSTURES}
    for name, value in capacity.items():
        low = 1 if name == "postures" else 0
        if not low <= value <= highs[name]:
            raise RunFolderError(f"{file}: capacity.{name} must be from {low} to {highs[name]}, got {describe(value)}")


def network_parameters(saved: dict[str, Any], config: dict[str, Any]) -> int:
    """An upper bound on the weights of the network ``config`` (a checked config's) builds for ``saved``'s sizes.

    The flat MLP's three layers (with the relative features appended to its input); the
    set encoder's token width is at most 128, whatever ``hidden`` says, so only the
    scores of its candidates grow with the run (counted once per candidate and unit).
    """
    hidden, candidates = config.get("hidden", BCConfig().hidden), saved["candidates"]
    if config.get("encoder") == "cnn":  # the convolutions (at most 64 x 66 x 16 weights each), then the head
        cells = image_shape(config.get("obs_mode", "topdown"), saved["features"])[1] // 2
        return 8 * 64 * 66 * 16 + 64 * min(cells, 16) ** 2 * hidden + (hidden + 1) * candidates
    if config.get("encoder", "mlp") != "mlp":
        width = min(hidden, 128)
        return 64 * width * width + candidates * width
    capacity = Capacity(**saved["capacity"])
    inputs = saved["features"]
    if config.get("relative", LEGACY_CONFIG["relative"]):
        rects = capacity.clutter + capacity.tables + capacity.obstacles
        inputs += 6 * capacity.objects + 4 * rects + 2 * capacity.clutter * capacity.objects
    return 2 * inputs + inputs * hidden + hidden * hidden + (hidden + 1) * (candidates + 2)


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
            raise RunFolderError(f"{file}: {key}.{name} must be a {expected.__name__}, got {describe(item)}")


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
    given: stable-baselines3's ``evaluate_policy(policy, env)`` gives none, so load the
    policy with that env. Raises :class:`RunFolderError` (bad input, a ``ValueError``) for
    anything that is not a loadable run folder, and nothing else.
    """
    kind = read_saved(path).get("kind")
    if not (isinstance(kind, str) and kind in registry.kinds()):
        read_config(path)  # raises: it says what is wrong (unknown or missing keys, the kind)
    return registry.loader(kind)(Path(path), env)


# ---------------------------------------------------------------------------- writing
def write_config(out: Path, config: dict[str, Any]) -> None:
    """Write ``config.json`` atomically."""
    out.mkdir(parents=True, exist_ok=True)
    write_atomically(out / CONFIG_FILE, (json.dumps(config, indent=2) + "\n").encode())


def write_metrics(out: Path, rows: list[dict[str, Any]]) -> None:
    """Write ``metrics.csv`` (all rows, atomically; the columns of the first row)."""
    if not rows:
        return
    text = io.StringIO(newline="")
    writer = csv.DictWriter(text, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
    write_atomically(out / METRICS_FILE, text.getvalue().encode())


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
    with atomic_file(out / CHECKPOINT_FILE) as file:
        torch.save(state, file)


def load_checkpoint(out: Path) -> dict[str, Any] | None:
    """The state in ``checkpoint.pt``, or None if there is none (``weights_only``: it runs no code).

    :class:`RunFolderError` unless it is a regular file of at most :data:`MAX_CHECKPOINT_BYTES`
    holding a dict of tensors whose floating-point values are all finite.
    """
    file = out / CHECKPOINT_FILE
    if not os.path.lexists(file):
        return None
    state = read_tensors(file, MAX_CHECKPOINT_BYTES)
    if not isinstance(state, dict):
        raise RunFolderError(f"{file} does not hold a training checkpoint (a dict of its state)")
    try:
        check_finite(file, state)
    except RecursionError:
        raise RunFolderError(f"{file} does not hold a training checkpoint: nested too deeply") from None
    return state


def checkpoint_counter(out: Path, checkpoint: dict[str, Any], key: str, high: int) -> int:
    """``checkpoint[key]`` (epochs, env steps, episodes done), an integer from 0 to ``high`` (the run's budget).

    A checkpoint that says more was done than the run's options ask for (or less than
    nothing) would mark the run complete untrained: :class:`RunFolderError`. So is a
    checkpoint without the counter, or whose ``metrics`` are not a list of rows.
    """
    file = out / CHECKPOINT_FILE
    value = checkpoint.get(key)
    if isinstance(value, torch.Tensor) and value.numel() == 1 and not value.is_floating_point():
        value = int(value)
    if not isinstance(value, int) or isinstance(value, bool):
        raise RunFolderError(f"{file}: {key} must be an integer, got {describe(value)}")
    if not 0 <= value <= high:
        raise RunFolderError(f"{file}: {key} {value:,} is not from 0 to {high:,} (this run's budget): "
                             "train into a new folder")  # fmt: skip
    rows = checkpoint.get("metrics")
    if not isinstance(rows, list) or not all(isinstance(row, dict) for row in rows):
        raise RunFolderError(f"{file}: metrics must be a list of rows")
    return value


def check_checkpoint_fields(file: Path, checkpoint: dict[str, Any], names: tuple[str, ...]) -> None:
    """:class:`RunFolderError` unless the checkpoint holds exactly the fields ``names`` (none missing, none unknown)."""
    missing = [name for name in names if name not in checkpoint]
    if missing:
        raise RunFolderError(f"{file}: missing fields {', '.join(missing)} (a training checkpoint holds "
                             f"{', '.join(names)})")  # fmt: skip
    unknown = [describe(key) for key in checkpoint if key not in names]
    if unknown:
        raise RunFolderError(f"{file}: unknown fields {', '.join(unknown[:5])} (a training checkpoint holds "
                             f"{', '.join(names)} only)")  # fmt: skip


def check_module_state(file: Path, field: str, state: Any, module: torch.nn.Module) -> None:
    """:class:`RunFolderError` unless ``state`` holds ``module``'s own tensors: the same names, shapes and dtypes.

    ``field`` names the checkpoint's field in the message (``network``, ``network.layers.0.weight``).
    """
    expected = module.state_dict()
    if not isinstance(state, dict):
        raise RunFolderError(f"{file}: {field} must be a network's state (a dict of tensors), got {_words(state)}")
    missing = [name for name in expected if name not in state]
    if missing:
        raise RunFolderError(f"{file}: {field} lacks {', '.join(missing[:5])}: it is not this run's network")
    unknown = [describe(name) for name in state if name not in expected]
    if unknown:
        raise RunFolderError(f"{file}: {field} holds {', '.join(unknown[:5])}, which this run's network has not")
    for name, tensor in expected.items():
        check_tensor_like(file, f"{field}.{name}", state[name], tensor)


def check_tensor_like(file: Path, field: str, value: Any, like: torch.Tensor) -> None:
    """:class:`RunFolderError` unless ``value`` is a plain (dense) tensor of ``like``'s shape and dtype."""
    if (
        not isinstance(value, torch.Tensor)
        or value.layout != torch.strided
        or value.shape != like.shape
        or value.dtype != like.dtype
    ):
        raise RunFolderError(f"{file}: {field} must be {_words(like)}, got {_words(value)}")


def check_adam_state(file: Path, field: str, state: Any, optimiser: torch.optim.Adam) -> None:
    """:class:`RunFolderError` unless ``state`` is a state of ``optimiser`` (Adam over the same parameters).

    Its parameter groups hold the same settings (a setting an older torch did not save may
    be missing) and parameter indices; each parameter's moments are tensors of that
    parameter's shape and dtype (the second moment never negative), its step a count >= 0.
    """
    if not isinstance(state, dict) or set(state) != {"state", "param_groups"}:
        raise RunFolderError(f"{file}: {field} must be an optimiser's state (state and param_groups)")
    fresh = optimiser.state_dict()["param_groups"]
    groups = state["param_groups"]
    if not isinstance(groups, list) or len(groups) != len(fresh):
        raise RunFolderError(f"{file}: {field}.param_groups must list {len(fresh)} group(s), got {_words(groups)}")
    for index, (group, own) in enumerate(zip(groups, fresh, strict=True)):
        _check_param_group(file, f"{field}.param_groups[{index}]", group, own)
    parameters = [p for group in optimiser.param_groups for p in group["params"]]
    moments = ("exp_avg", "exp_avg_sq", *(("max_exp_avg_sq",) if optimiser.defaults.get("amsgrad") else ()))
    entries = state["state"]
    if not isinstance(entries, dict):
        raise RunFolderError(f"{file}: {field}.state must be a dict of the parameters' moments")
    for index, entry in entries.items():
        where = f"{field}.state[{describe(index)}]"
        if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < len(parameters):
            raise RunFolderError(f"{file}: {where}: not one of the {len(parameters)} parameters' indices")
        if not isinstance(entry, dict) or set(entry) != {"step", *moments}:
            raise RunFolderError(f"{file}: {where} must hold step, {', '.join(moments)}")
        _check_step(file, f"{where}.step", entry["step"])
        for moment in moments:
            check_tensor_like(file, f"{where}.{moment}", entry[moment], parameters[index].detach())
            if moment != "exp_avg" and bool((entry[moment] < 0).any()):
                raise RunFolderError(f"{file}: {where}.{moment} holds negative numbers (a mean of squares)")


def _check_param_group(file: Path, where: str, group: Any, own: dict[str, Any]) -> None:
    """One saved parameter group: this run's settings (the learning rate, ...) and parameter indices."""
    if not isinstance(group, dict):
        raise RunFolderError(f"{file}: {where} must be a dict of settings, got {_words(group)}")
    for key in ("params", "lr", "betas", "eps", "weight_decay"):
        if key not in group:
            raise RunFolderError(f"{file}: {where} lacks {key}")
    for key, value in group.items():
        if key not in own:
            raise RunFolderError(f"{file}: {where} holds {describe(key)}, which this run's optimiser has not")
        if not _same_setting(value, own[key]):
            raise RunFolderError(f"{file}: {where}.{key} is {_words(value)}, not this run's {describe(own[key])}")


def _same_setting(value: Any, own: Any) -> bool:
    """Whether a saved setting is this run's: the same type and value (tuples and lists element by element)."""
    if isinstance(own, tuple | list):
        return (
            type(value) is type(own)
            and len(value) == len(own)
            and all(_same_setting(v, o) for v, o in zip(value, own, strict=True))
        )
    return type(value) is type(own) and bool(value == own)


def _check_step(file: Path, field: str, step: Any) -> None:
    """An optimiser's step count: a number, or a one-element real tensor, finite and >= 0."""
    if isinstance(step, torch.Tensor) and step.numel() == 1 and not step.is_complex() and step.dtype != torch.bool:
        step = step.item()
    if not isinstance(step, int | float) or isinstance(step, bool) or not math.isfinite(step) or step < 0:
        raise RunFolderError(f"{file}: {field} must be a count of steps >= 0, got {_words(step)}")


def check_generator_state(file: Path, field: str, state: Any, generator: torch.Generator) -> None:
    """:class:`RunFolderError` unless ``state`` is a state ``generator`` takes (tried on a fresh generator)."""
    check_tensor_like(file, field, state, generator.get_state())
    try:
        torch.Generator(device=generator.device).set_state(state)
    except RuntimeError as error:  # the bytes of no state (torch checks the Mersenne Twister's own)
        raise RunFolderError(f"{file}: {field} is not a random generator's state ({_short(error)})") from None


def check_metric_rows(file: Path, field: str, rows: Any, columns: tuple[str, ...], count: int) -> None:
    """:class:`RunFolderError` unless ``rows`` are ``count`` rows of exactly ``columns``, each a finite number."""
    if not isinstance(rows, list) or len(rows) != count:
        raise RunFolderError(f"{file}: {field} must list {count} row(s) (one per {columns[0]} done), "
                             f"got {_words(rows)}")  # fmt: skip
    for index, row in enumerate(rows):
        if not isinstance(row, dict):
            raise RunFolderError(f"{file}: {field}[{index}] must be a row of {', '.join(columns)}, got {_words(row)}")
        missing, unknown = [c for c in columns if c not in row], [describe(c) for c in row if c not in columns]
        if missing or unknown:
            wrong = f"lacks {', '.join(missing)}" if missing else f"holds {', '.join(unknown[:5])}"
            raise RunFolderError(f"{file}: {field}[{index}] {wrong} (a row holds {', '.join(columns)})")
        for column, value in row.items():
            if not isinstance(value, int | float) or isinstance(value, bool) or not math.isfinite(value):
                raise RunFolderError(f"{file}: {field}[{index}].{column} must be a number, got {_words(value)}")


def _words(value: Any) -> str:
    """A value in a message: a tensor by its dtype and shape (never its numbers), anything else cut short."""
    if isinstance(value, torch.Tensor):
        layout = "" if value.layout == torch.strided else f"{value.layout} "
        return f"a {layout}{str(value.dtype).removeprefix('torch.')} tensor of shape {tuple(value.shape)}"
    if isinstance(value, list | dict):
        return f"a {type(value).__name__} of {len(value)}"
    return describe(value)


def read_tensors(file: Path, max_bytes: int) -> Any:
    """What ``torch.save`` wrote to ``file``, read with ``weights_only`` (tensors, numbers, strings, lists, dicts).

    Only a regular file of at most ``max_bytes`` is read (opened without blocking, its
    kind and size checked on the open file: no FIFO, device or symbolic link swapped in
    between). Anything that is not such a file of tensors (random bytes, a text file, a
    pickle of other objects, which is not loaded) is a :class:`RunFolderError`; its
    message never suggests loading it otherwise.
    """
    try:
        descriptor = os.open(file, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as error:
        raise RunFolderError(f"{file} cannot be read: {error.strerror or error}") from None
    mode = os.fstat(descriptor)
    if not stat.S_ISREG(mode.st_mode) or mode.st_size > max_bytes:
        os.close(descriptor)
        if not stat.S_ISREG(mode.st_mode):
            raise RunFolderError(f"{file} is not a regular file: a run folder holds files torch.save wrote")
        raise RunFolderError(f"{file} is {mode.st_size:,} bytes, more than the {max_bytes:,} it may have")
    with os.fdopen(descriptor, "rb") as stream:
        try:
            return torch.load(stream, weights_only=True, map_location="cpu")
        except pickle.UnpicklingError:
            raise RunFolderError(
                f"{file} is not a file of tensors that torch.save wrote: it is not loaded (nothing in a run folder "
                "runs code)"
            ) from None
        except Exception as error:  # a stranger's bytes: any failure of the reader is bad input
            raise RunFolderError(f"{file} is not a file of tensors that torch.save wrote ({_short(error)})") from None


def _short(error: BaseException) -> str:
    """The error's type and the first line of its message, cut short."""
    first = (str(error).splitlines() or [""])[0][:160]
    return f"{type(error).__name__}: {first}" if first else type(error).__name__


def check_finite(file: Path, value: Any, where: str = "") -> None:
    """:class:`RunFolderError` if a floating-point tensor in ``value`` (dicts, lists of them) holds NaN or infinity.

    A tensor that is not dense (sparse, say: ``torch.save`` keeps any layout) is refused too:
    a run folder holds dense tensors only, and other layouts lack the operations checked here.
    """
    if isinstance(value, torch.Tensor):
        shown = describe(where) if where else "it holds"
        if value.layout != torch.strided:
            raise RunFolderError(f"{file}: the tensor {shown} is not dense but {value.layout} (run folders hold dense)")
        if value.is_floating_point() and not bool(torch.isfinite(value).all()):
            raise RunFolderError(f"{file}: the weights {shown} are not all finite numbers (NaN or inf)")
    elif isinstance(value, dict):
        for key, item in value.items():
            check_finite(file, item, f"{where}.{key}" if where else str(key))
    elif isinstance(value, list | tuple):
        for k, item in enumerate(value):
            check_finite(file, item, f"{where}[{k}]")


def save_weights(out: Path, network: torch.nn.Module) -> None:
    with atomic_file(out / WEIGHTS_FILE) as file:
        torch.save(network.state_dict(), file)


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
               candidates: int, features: int, data: dict[str, Any],
               observation: dict[str, Any] | None = None) -> dict[str, Any]:  # fmt: skip
    """The ``config.json`` of a run (see above); ``observation``: the env's observation keywords.

    Without ``observation``, an image network's is its mode with the env's default image
    options (:func:`observation_of`) and a state network's is not written (its run folders
    stay as they were).
    """
    mode = getattr(config, "obs_mode", "state")
    if observation is None and mode != "state":
        observation = observation_of(mode, {})
    extra = {} if observation is None else {"observation": dict(observation)}
    return {
        **extra,
        "kind": kind,
        "interface": INTERFACE,
        "env_id": env_id_of(INTERFACE),
        "options": options,
        "config": asdict(config),
        "capacity": asdict(capacity),
        "candidates": candidates,
        "features": features,
        "data": data,
    }


def observation_of(obs_mode: str, env_options: dict[str, Any]) -> dict[str, Any]:
    """``config.json``'s ``observation`` for a network of ``obs_mode`` trained in an env made with ``env_options``.

    The mode and that mode's image options among ``env_options`` (a dataset's env
    keywords, say); the options not given are the env's defaults, written out.
    """
    mode = get_mode(obs_mode)
    given = {key: value for key, value in env_options.items() if key in mode.option_names}
    kept = mode.resolved(given)
    return {"obs_mode": obs_mode, **{key: value for key, value in kept.items() if value is not None}}


def finish_run(folder: Path, network: torch.nn.Module, config_json: dict[str, Any]) -> None:
    """Write the final weights and mark the run complete."""
    save_weights(folder, network)
    write_config(folder, {**config_json, "complete": True})
