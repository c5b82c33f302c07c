"""Which policies the benchmark knows: a registry of named factories, and run folders.

A policy is named by a registry key (``expert``, ``random``, ``greedy``) or by the
path of a run folder (anything :func:`training.load_policy` loads). Each
acts in one *interface*: ``env`` (``FetchCarryPush-v0``'s ``MultiDiscrete`` phase
actions) or ``phases`` (``FetchCarryPushPhases-v0``'s ``Discrete`` candidate phases);
the benchmark builds the env that interface needs and hands the policy its masks as
``action_masks=`` (stable-baselines3's ``predict`` protocol, as MaskablePPO takes them).

A run folder's ``config.json`` says its interface (``"interface": "env"`` or
``"phases"``); a run without the key that stores ``candidates`` (the size of the
candidate list, as BC runs do) acts in ``phases``. Its ``capacity`` (observation
slots), if stored, is the env's.

Adding a named policy is one line in :data:`FACTORIES`: the module and class to build
it from (the class is called with the env), and its interface. A factory whose module
is not installed is refused with a message when asked for, and is not listed.
"""

from __future__ import annotations

import importlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from training.evaluation.errors import BenchmarkError

INTERFACES = {"env": "FetchCarryPush-v0", "phases": "FetchCarryPushPhases-v0"}  # interface -> env id
EXPERT, RANDOM = "expert", "random"  # the reference policies every benchmark runs
EXPERT_TIME_LIMIT = 10.0  # seconds per planning call of the expert


@dataclass(frozen=True)
class Factory:
    """How to build a named policy: ``module.attribute(env, **options)``, acting in ``interface``."""

    module: str
    attribute: str
    interface: str
    options: dict[str, Any] = field(default_factory=dict)
    seeded: bool = False  # reset(seed) before each episode (the episode's seed)


FACTORIES: dict[str, Factory] = {
    EXPERT: Factory("expert.policy", "ExpertPolicy", "env", {"time_limit": EXPERT_TIME_LIMIT}),
    RANDOM: Factory("training.policies.random", "RandomMaskedPolicy", "env", seeded=True),
    "random-phases": Factory("training.policies.random_phases", "RandomPhasePolicy", "phases", seeded=True),
    "greedy": Factory("training.policies.greedy", "GreedyPolicy", "env"),
}
"""Named policies: one line each."""


@dataclass(frozen=True)
class PolicySpec:
    """A policy to benchmark, as plain data (it crosses process boundaries to the workers)."""

    name: str  # the label in results: a registry key or the run folder's name
    interface: str  # "env" or "phases"
    factory: str | None = None  # a key of FACTORIES, or
    run: str | None = None  # the path of a run folder
    env_options: dict[str, Any] = field(default_factory=dict)  # extra gym.make options (capacity)

    @property
    def env_id(self) -> str:
        return INTERFACES[self.interface]


def available() -> list[str]:
    """The registry keys whose module is installed."""
    out = []
    for key, factory in FACTORIES.items():
        try:
            importlib.import_module(factory.module)
        except ModuleNotFoundError:
            continue
        out.append(key)
    return out


def resolve(name: str) -> PolicySpec:
    """The :class:`PolicySpec` of a registry key or a run folder's path; :class:`BenchmarkError` otherwise."""
    if name in FACTORIES:
        factory = FACTORIES[name]
        try:
            importlib.import_module(factory.module)
        except ModuleNotFoundError:
            raise BenchmarkError(f"policy {name!r} is not available here ({factory.module} is not installed)") from None
        return PolicySpec(name, factory.interface, factory=name)
    path = Path(name)
    if not path.exists():
        if "/" in name or "\\" in name:
            raise BenchmarkError(f"no run folder at {name}")
        known = ", ".join(available())
        raise BenchmarkError(f"unknown policy {name!r}: give one of {known} or a run folder")
    return _run_spec(path)


def _run_spec(path: Path) -> PolicySpec:
    config_path = path / "config.json"
    if not path.is_dir() or not config_path.is_file():
        raise BenchmarkError(f"{path} is not a run folder (no config.json)")
    try:
        config = json.loads(config_path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise BenchmarkError(f"{config_path} is not valid JSON: {error}") from None
    if not isinstance(config, dict):
        raise BenchmarkError(f"{config_path} does not hold a run's configuration")
    interface = config.get("interface", "phases" if "candidates" in config else "env")
    if interface not in INTERFACES:
        raise BenchmarkError(f"{config_path}: unknown interface {interface!r}; known: {', '.join(INTERFACES)}")
    options = {"capacity": config["capacity"]} if isinstance(config.get("capacity"), dict) else {}
    # Check that it loads here, so that a broken run folder is bad input, not a crash in a worker.
    try:
        from training.learners.runs import load_policy

        load_policy(path)
    except (ValueError, OSError, KeyError, TypeError, RuntimeError) as error:
        raise BenchmarkError(f"{path} does not load as a policy: {error}") from None
    return PolicySpec(path.name or str(path), interface, run=str(path.resolve()), env_options=options)


def resolve_all(names: list[str]) -> list[PolicySpec]:
    """Resolve every name; the labels must be distinct (two run folders of one name are refused)."""
    specs = [resolve(name) for name in names]
    labels = [s.name for s in specs]
    repeated = sorted({label for label in labels if labels.count(label) > 1})
    if repeated:
        raise BenchmarkError(f"policies named twice: {', '.join(repeated)} (run folders need distinct names)")
    return specs


def build(spec: PolicySpec, env: Any) -> Any:
    """The policy ``spec`` names, built for ``env`` (speaks stable-baselines3's ``predict`` protocol)."""
    if spec.run is not None:
        from training.learners.runs import load_policy

        return load_policy(spec.run, env)
    factory = FACTORIES[spec.factory]
    cls = getattr(importlib.import_module(factory.module), factory.attribute)
    return cls(env, **factory.options)


def start_episode(spec: PolicySpec, policy: Any, seed: int) -> None:
    """Prepare ``policy`` for a new episode: forget the last one; a seeded policy draws from ``seed``."""
    reset = getattr(policy, "reset", None)
    if reset is None:
        return
    if spec.factory is not None and FACTORIES[spec.factory].seeded:
        reset(seed=seed)
    else:
        reset()
