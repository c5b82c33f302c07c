"""The one resolver: a policy's name, a run folder or a user's factory -> a policy for an env.

A policy is named by

- a registry key of :data:`FACTORIES` (``expert``, ``random``, ``random-phases``,
  ``greedy``, ``expert-phases``): the module and class to build it from, called with the env;
- the path of a run folder (anything :func:`training.load_policy` loads); its
  ``config.json`` says its interface (``"interface": "env"`` or ``"phases"``; a run
  without the key that stores ``candidates``, as BC runs do, acts in ``phases``) and its
  ``capacity`` (observation slots), if stored, is the env's;
- ``NAME@published``, a run folder that ships with the repository (:mod:`training.published`);
- ``package.module:factory``, a user's function (or class) called with the env that
  returns a :class:`~training.policies.protocol.Policy`; it acts in ``phases`` unless
  the factory has an attribute ``interface = "env"``. The module is imported as
  ``python -m`` would find it: the working folder :func:`resolve` ran in comes first on
  the import path, for that import only (then the installed packages); the factory and
  every answer of its policy are checked (:mod:`training.policies.user`: a factory that
  raises or gives no policy, an answer that is no action of the env, is bad input naming
  ``module:factory``). Naming it runs the user's code, as running their script would.

Each acts in one *interface* (:mod:`training.envs`): ``env`` (``FetchCarryPush-v0``'s
``MultiDiscrete`` phase actions) or ``phases`` (``FetchCarryPushPhases-v0``'s
``Discrete`` candidate phases). :func:`resolve` turns a name into a :class:`PolicySpec`
(plain data that crosses process boundaries) and :func:`build` a spec into the policy,
in the process that runs it. Adding a named policy is one line in :data:`FACTORIES`;
a factory whose module is not installed is refused with a message when asked for, and
is not listed.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fetchcarry_env.observations import get_mode, image_options, mode_names
from training.envs import INTERFACES
from training.errors import BenchmarkError
from training.policies.protocol import Policy
from training.policies.user import describe_raised, user_policy
from training.published import SUFFIX, published_names, published_run

EXPERT, RANDOM = "expert", "random"  # the reference policies every benchmark runs
EXPERT_TIME_LIMIT = 10.0  # seconds per planning call of the expert
PLANNING = {"time_limit": EXPERT_TIME_LIMIT}  # the options of a planning policy


@dataclass(frozen=True)
class Factory:
    """How to build a named policy: ``module.attribute(env, **options)``, acting in ``interface``."""

    module: str
    attribute: str
    interface: str
    options: dict[str, Any] = field(default_factory=dict)


FACTORIES: dict[str, Factory] = {
    EXPERT: Factory("expert.policy", "ExpertPolicy", "env", PLANNING),
    RANDOM: Factory("training.policies.random", "RandomMaskedPolicy", "env"),
    "random-phases": Factory("training.policies.random", "RandomPhasePolicy", "phases"),
    "greedy": Factory("training.policies.greedy", "GreedyPolicy", "env"),
    "expert-phases": Factory("training.policies.phase_expert", "PhaseExpert", "phases", PLANNING),
}
"""Named policies: one line each (the module is imported when the policy is asked for)."""

RECORDING = {("env", "expert"): EXPERT, ("env", "random"): RANDOM,
             ("phases", "expert"): "expert-phases", ("phases", "random"): "random-phases"}  # fmt: skip
"""What ``fetchcarry generate --policy P --interface I`` records with: (interface, P) -> a key of FACTORIES."""


@dataclass(frozen=True)
class PolicySpec:
    """A policy to run, as plain data (it crosses process boundaries to the workers)."""

    name: str  # the label in results: a registry key, the run folder's name, or module:factory
    interface: str  # "env" or "phases"
    factory: str | None = None  # a key of FACTORIES, or
    run: str | None = None  # the path of a run folder, or
    user: str | None = None  # package.module:factory
    env_options: dict[str, Any] = field(default_factory=dict)  # extra gym.make options (capacity)
    folder: str | None = None  # module:factory's working folder, first on the import path where it is built

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
    """The :class:`PolicySpec` of a registry key, a run folder's path or ``module:factory``; else ``BenchmarkError``."""
    if name in FACTORIES:
        factory = FACTORIES[name]
        try:
            importlib.import_module(factory.module)
        except ModuleNotFoundError:
            raise BenchmarkError(f"policy {name!r} is not available here ({factory.module} is not installed)") from None
        return PolicySpec(name, factory.interface, factory=name)
    if name.endswith(SUFFIX):
        try:
            return _run_spec(published_run(name))
        except KeyError as error:
            raise BenchmarkError(error.args[0]) from None
    path = Path(name)
    if not path.exists():
        if _is_factory_name(name):
            folder = os.getcwd()  # a worker's may differ (Ray's): the spec carries it
            return PolicySpec(name, _user_interface(name, folder), user=name, folder=folder)
        if "/" in name or "\\" in name:
            raise BenchmarkError(f"no run folder at {name}")
        known = ", ".join(available())
        raise BenchmarkError(
            f"unknown policy {name!r}: give one of {known}, a run folder, NAME{SUFFIX} "
            f"({', '.join(published_names())}) or package.module:factory"
        )
    return _run_spec(path)


def _is_factory_name(name: str) -> bool:
    module, colon, attribute = name.partition(":")
    return bool(colon) and all(part.isidentifier() for part in [*module.split("."), *attribute.split(".")])


def _user_factory(name: str, folder: str | None) -> Callable[[Any], Any]:
    """The callable ``package.module:factory`` names, imported with ``folder`` first on the import path.

    ``BenchmarkError`` if the module cannot be imported (or raises as it runs) or has no such callable.
    """
    module_name, _, attribute = name.partition(":")
    try:
        with _first_on_import_path(folder):
            target: Any = importlib.import_module(module_name)
    except ImportError as error:
        where = f"the working folder {folder} and " if folder is not None else ""
        raise BenchmarkError(
            f"policy {name!r}: cannot import {module_name} from {where}the installed packages ({error})"
        ) from None
    except Exception as error:  # the user's module failed as it ran
        raise BenchmarkError(f"policy {name!r}: importing {module_name} raised {describe_raised(error)}") from error
    for part in attribute.split("."):
        target = getattr(target, part, None)
    if not callable(target):
        raise BenchmarkError(f"policy {name!r}: {module_name} has no callable {attribute}")
    return target


@contextlib.contextmanager
def _first_on_import_path(folder: str | None) -> Iterator[None]:
    """Run the block with ``folder`` first on ``sys.path`` (where ``python -m`` puts the working folder), then not."""
    if folder is None:
        yield
        return
    sys.path.insert(0, folder)
    importlib.invalidate_caches()  # a module written since the import system last listed the folder
    try:
        yield
    finally:
        with contextlib.suppress(ValueError):
            sys.path.remove(folder)


def _user_interface(name: str, folder: str | None) -> str:
    interface = getattr(_user_factory(name, folder), "interface", "phases")
    if interface not in INTERFACES:
        raise BenchmarkError(f"policy {name!r}: interface must be one of {', '.join(INTERFACES)}, got {interface!r}")
    return interface


def _run_spec(path: Path) -> PolicySpec:
    if not path.is_dir():
        raise BenchmarkError(f"{path} is not a run folder")
    # Load it here, so that a broken run folder is bad input, not a crash in a worker; load_policy
    # reads config.json within bounds (a regular file of bounded size) and checks it first.
    from training.learners.runs import load_policy, read_saved  # torch at its top

    try:
        load_policy(path)
        config = read_saved(path)
    except (ValueError, OSError) as error:
        raise BenchmarkError(f"{path} does not load as a policy: {error}") from None
    interface = config.get("interface", "phases" if "candidates" in config else "env")
    if interface not in INTERFACES:
        raise BenchmarkError(f"{path / 'config.json'}: unknown interface {interface!r}; known: {', '.join(INTERFACES)}")
    options = {"capacity": config["capacity"]} if isinstance(config.get("capacity"), dict) else {}
    options.update(run_image_options(config))
    return PolicySpec(path.name or str(path), interface, run=str(path.resolve()), env_options=options)


def run_image_options(config: dict[str, Any]) -> dict[str, Any]:
    """The env's observation options a run folder's network needs (``{}`` for the state).

    ``config`` is the run folder's ``config.json`` (as read): its ``observation`` (the
    mode and image options it was trained with, :mod:`training.learners.runs`), or, for a
    run folder written before it was recorded, the image size read from the network's
    input (the map's frame the default, ``world``).
    """
    network = config.get("config")
    obs_mode = network.get("obs_mode", "state") if isinstance(network, dict) else "state"
    if obs_mode not in mode_names() or not get_mode(obs_mode).keys or not isinstance(config.get("features"), int):
        return {}  # an unknown mode is refused when the run folder loads
    recorded = config.get("observation")
    if isinstance(recorded, dict) and recorded.get("obs_mode") == obs_mode:
        return dict(recorded)  # checked when the run folder loads
    try:
        return image_options(obs_mode, config["features"])
    except ValueError:
        return {}


def run_obs_mode(spec: PolicySpec) -> str | None:
    """The observation mode the network of run folder ``spec`` sees (``topdown``, ``rgbd``), or None.

    None for a state network (it reads the state vector, which every mode's observation
    holds) and for a policy that is not a run folder.
    """
    return spec.env_options.get("obs_mode") if spec.run is not None else None


def check_obs_mode(spec: PolicySpec, obs_mode: str | None) -> None:
    """``BenchmarkError`` when ``obs_mode`` (given on the command line; None: not given) is not what ``spec`` sees.

    A run folder of an image network acts only in the mode it was trained in; a state
    network or a named policy acts in any mode (the state vector is in every one).
    """
    check_run_obs_mode(spec.name, run_obs_mode(spec), obs_mode)


def check_run_obs_mode(name: str, own: str | None, obs_mode: str | None) -> None:
    """``BenchmarkError`` unless run folder ``name`` (its network sees ``own``; None: state) acts in ``obs_mode``."""
    if obs_mode is not None and own is not None and own != obs_mode:
        raise BenchmarkError(
            f"run folder {name} was trained on obs_mode {own!r}, not {obs_mode!r}: leave --obs-mode out "
            f"(a run folder's env is made in its own mode) or give --obs-mode {own}"
        )


def resolve_all(names: list[str]) -> list[PolicySpec]:
    """Resolve every name; the labels must be distinct (two run folders of one name are refused)."""
    specs = [resolve(name) for name in names]
    labels = [s.name for s in specs]
    repeated = sorted({label for label in labels if labels.count(label) > 1})
    if repeated:
        raise BenchmarkError(f"policies named twice: {', '.join(repeated)} (run folders need distinct names)")
    return specs


def build(spec: PolicySpec, env: Any, *, time_limit: float | None = None) -> Policy:
    """The policy ``spec`` names, built for ``env``; ``time_limit`` (seconds per plan) overrides a planner's."""
    if spec.run is not None:
        from training.learners.runs import load_policy  # torch: imported only when a run folder is used

        return load_policy(spec.run, env)
    if spec.user is not None:
        return user_policy(spec.user, _user_factory(spec.user, spec.folder), env)
    factory = FACTORIES[spec.factory]
    options = dict(factory.options)
    if time_limit is not None and "time_limit" in options:
        options["time_limit"] = time_limit
    return getattr(importlib.import_module(factory.module), factory.attribute)(env, **options)


def recording_policy(name: str, interface: str, env: Any, *, time_limit: float) -> Policy:
    """The policy ``fetchcarry generate --policy name --interface interface`` records with (:data:`RECORDING`)."""
    return build(resolve(RECORDING[interface, name]), env, time_limit=time_limit)
