"""The learned baselines ``fetchcarry train`` knows: ``kind -> Learner``, each registered once.

A :class:`Learner` gives its options dataclass (the command line's options are made from
its fields: :mod:`training.learners.options`), the function that trains a run folder of
it, the function that loads one (unless its policy is the BC network every built-in
kind acts through), and the texts of ``fetchcarry train KIND --help``. The contract:

- ``train(**fields, out=RUN_DIR, ...)``: called with the options dataclass's top-level
  fields as keyword arguments, the run folder ``out`` and, for a ``resumable`` learner,
  ``resume`` and ``progress``; for a ``pool`` learner (one that labels on the worker
  pool of ``fetchcarry generate``) also ``workers`` and ``backend``. It writes the run
  folder: ``config.json`` with the ``kind`` and ``complete`` when done.
- ``load(path, env)``: the run folder's policy (:class:`training.policies.Policy`); by
  default :data:`NETWORK_LOADER`, the BC network's (the built-in kinds').

The functions are named (``"package.module:function"``), not imported here: a learner's
module imports torch or stable-baselines3 at its top, while this module is imported
whenever the ``fetchcarry`` parser is built (for every command, ``fetchcarry plan``
included, which must stay fast) and by :mod:`training.learners.runs`, which the learner
modules themselves import. :func:`train` and :func:`loader` import a learner's module
only when a run of it is trained or loaded.

A new learner is one module and one :func:`register` call (``docs/design.md``, "Adding a
learned baseline"): put the call at the end of this module to make it a built-in, so that
every process (a benchmark's workers too) knows it.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass, fields, is_dataclass
from typing import Any

from fetchcarry_env.errors import InputError
from training.learners.options import BCRun, DaggerRun, EnsembleRun, PPORun

NETWORK_LOADER = "training.learners.imitation:load_network_policy"
"""The ``load`` of the run folders whose policy is the BC network (bc, dagger, ppo, ensemble)."""

Summary = Callable[[Any, list[dict[str, float]], str], str]
"""``summary(options, rows, out)``: the lines ``fetchcarry train`` prints (``rows``: ``metrics.csv``, or [])."""


class UnknownLearnerError(InputError):
    """A kind of run that no learner is registered for."""


@dataclass(frozen=True)
class Learner:
    """One learned baseline: what ``fetchcarry train KIND`` takes, and how its run folders train and load."""

    kind: str  # config.json's "kind" and the command's name
    options: type  # a frozen dataclass of options.option / options.nested fields (light to import)
    train: str  # "package.module:function", called as the module docstring says
    help: str  # one line for ``fetchcarry train --help``
    # "package.module:function" called as refuse(options) before training, raising EvaluationSeedError when the run
    # would train on evaluation seeds or a split's scenario (training.learners.refusals); None only for a learner that
    # trains on no episodes (ensemble). No default: a new learner says which.
    refuse: str | None
    description: str = ""  # ``fetchcarry train KIND --help``
    load: str = NETWORK_LOADER  # "package.module:function", called as load(path, env)
    summary: Summary | None = None  # None: "KIND trained" and the run folder
    resumable: bool = True  # takes resume= and progress= (--resume, --no-progress; Ctrl-C keeps its checkpoint)
    pool: bool = False  # takes workers= and backend= (--workers, --backend)
    epilog: str | None = None  # None: the run folder's contents and exit statuses

    def __post_init__(self) -> None:
        if not (isinstance(self.options, type) and is_dataclass(self.options)):
            raise TypeError(f"{self.kind}: options must be a dataclass, got {self.options!r}")
        for reference in (self.train, self.load, *([self.refuse] if self.refuse else [])):
            if reference.count(":") != 1:
                raise ValueError(f"{self.kind}: expected 'package.module:function', got {reference!r}")

    def describe(self, options: Any, rows: list[dict[str, float]], out: str) -> str:
        """What ``fetchcarry train`` prints once ``options`` trained into ``out``."""
        if self.summary is None:
            return f"{self.kind} trained\nrun folder {out}"
        return self.summary(options, rows, out)


_LEARNERS: dict[str, Learner] = {}


def register(learner: Learner) -> Learner:
    """Add ``learner`` (its kind must be new: a second registration is a programming error)."""
    if learner.kind in _LEARNERS:
        raise ValueError(f"a learner of kind {learner.kind!r} is registered already")
    _LEARNERS[learner.kind] = learner
    return learner


def unregister(kind: str) -> None:
    """Remove the learner of ``kind`` (tests that register a throwaway one)."""
    _LEARNERS.pop(kind, None)


def learners() -> tuple[Learner, ...]:
    """Every registered learner, in registration order."""
    return tuple(_LEARNERS.values())


def kinds() -> tuple[str, ...]:
    """The registered kinds, in registration order."""
    return tuple(_LEARNERS)


def get(kind: str) -> Learner:
    """The learner of ``kind``; :class:`UnknownLearnerError` (bad input) if there is none."""
    learner = _LEARNERS.get(kind)
    if learner is None:
        raise UnknownLearnerError(f"unknown kind of run {kind!r}: known {', '.join(_LEARNERS)}")
    return learner


def resolve(reference: str) -> Callable[..., Any]:
    """The function ``"package.module:function"`` names (importing its module)."""
    module, name = reference.split(":")
    return getattr(importlib.import_module(module), name)


def loader(kind: str) -> Callable[..., Any]:
    """The ``load(path, env)`` of ``kind``'s learner (importing its module)."""
    return resolve(get(kind).load)


def train(
    kind: str, options: Any, out: str, *, resume: bool = False, progress: bool = True, workers: int = 1,
    backend: str = "process",
) -> Any:  # fmt: skip
    """Train ``options`` (the options dataclass of ``kind``) into the run folder ``out``; return what train returns."""
    learner = get(kind)
    if not isinstance(options, learner.options):
        raise TypeError(f"{kind} trains {learner.options.__name__}, got {type(options).__name__}")
    arguments: dict[str, Any] = {f.name: getattr(options, f.name) for f in fields(options)}
    arguments["out"] = out
    if learner.resumable:
        arguments.update(resume=resume, progress=progress)
    if learner.pool:
        arguments.update(workers=workers, backend=backend)
    return resolve(learner.train)(**arguments)


# ---------------------------------------------------------------------------- the built-in learners
def _bc_summary(options: BCRun, rows: list[dict[str, float]], out: str) -> str:
    last = rows[-1]
    return (f"bc ({options.config.encoder}) on {options.dataset}: {int(last['epoch'])} epochs, loss "
            f"{last['loss']:.3f}, accuracy {last['accuracy']:.1%}\nrun folder {out}")  # fmt: skip


def _dagger_summary(options: DaggerRun, rows: list[dict[str, float]], out: str) -> str:
    last = rows[-1]
    return (f"dagger ({options.config.encoder}) on {options.family}: {int(last['iteration'])} iterations, "
            f"{int(last['expert_labels'])} expert labels, held-out success {last['heldout_success']:.1%}\n"
            f"run folder {out}")  # fmt: skip


def _ppo_summary(options: PPORun, rows: list[dict[str, float]], out: str) -> str:
    last = rows[-1] if rows else {}
    return (f"ppo ({options.options.encoder}) on {options.family}: {int(last.get('steps', 0))} env steps, recent "
            f"training success {last.get('success', float('nan')):.1%}, held-out success "
            f"{last.get('heldout_success', float('nan')):.1%}\nrun folder {out}")  # fmt: skip


def _ensemble_summary(options: EnsembleRun, rows: list[dict[str, float]], out: str) -> str:
    return f"ensemble of {len(options.members)} runs\nrun folder {out}"


register(Learner(
    "bc", BCRun, "training.learners.imitation:train_bc_run",
    help="behaviour cloning on a Minari dataset recorded with --interface phases",
    refuse="training.learners.refusals:refuse_bc",
    description="Behaviour cloning: a network scores every candidate phase from the observation, trained with "
    "cross-entropy on the expert's choices among the allowed candidates of a dataset made by "
    "'fetchcarry generate ... --interface phases'.",
    summary=_bc_summary,
))  # fmt: skip
register(Learner(
    "dagger", DaggerRun, "training.learners.dagger:train_dagger",
    help="DAgger: the learner acts, the MILP expert labels the states it visits",
    refuse="training.learners.refusals:refuse_dagger",
    description="DAgger: BC on expert demonstrations, then iterations in which the learner acts on new seeds of "
    "the family, the MILP expert labels every state it visits (mapped to candidates; an action no candidate "
    "expresses gives no label) and the network is retrained on the aggregate. Labelling runs on the same worker "
    "pool (or Ray) as fetchcarry generate. metrics.csv: one row per iteration with the expert labels so far and "
    "the success on held-out seeds.",
    summary=_dagger_summary, pool=True,
))  # fmt: skip
register(Learner(
    "ppo", PPORun, "training.learners.ppo:train_ppo",
    help="MaskablePPO (sb3-contrib) on the candidate phases with the learning reward",
    refuse="training.learners.refusals:refuse_ppo",
    description="sb3-contrib's MaskablePPO on FetchCarryPushPhases-v0 with the learning reward (potential-shaped "
    "progress, refusals cost more than moving). The actor is the BC network of --encoder, so --init RUN_DIR (a bc "
    "or dagger run of the same encoder) starts it from those weights. metrics.csv: one row per rollout with env "
    "steps, wall-clock seconds of training (evaluations left out), the training episodes' success, return and the "
    "paper's travel cost, and every --eval-every steps and at the end the success and travel cost on "
    "--eval-episodes held-out seeds (heldout_success, heldout_cost).",
    summary=_ppo_summary,
))  # fmt: skip
register(Learner(
    "ensemble", EnsembleRun, "training.learners.ensemble:make_ensemble",
    help="combine trained run folders into one policy (no further training)",
    refuse=None,
    description="Combine two or more finished run folders (bc, dagger or ppo, the same observation capacity) into "
    "one run folder whose policy acts on the mean of their log-probabilities: a candidate ranks first when the "
    "members agree on it. The members' weights are copied, so the folder stands alone. For example the three "
    "training seeds of dagger-aimed of a reproduction.",
    summary=_ensemble_summary, resumable=False,
    epilog="Exit status: 0 written, 2 bad input (a member that is not a finished run folder, members that score "
    "other candidates, an OUT that holds a run).",
))  # fmt: skip
