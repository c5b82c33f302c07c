"""Every ``fetchcarry`` command: its one line of help and the modules that add it.

``fetchcarry --help`` lists the commands from this table alone, and ``fetchcarry
COMMAND ...`` imports only the modules of that command, so that a command starts without
loading what the others need (torch for ``train``, SciPy's statistics for
``leaderboard``). This module imports no command module.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

from fetchcarry_env.errors import InputError


class Entry(NamedTuple):
    """A top-level command: the line ``fetchcarry --help`` shows and the modules whose ``register`` adds it."""

    help: str
    modules: tuple[str, ...]


COMMANDS: dict[str, Entry] = {
    "demo": Entry(
        "the expert delivers an object whose goal is covered: a picture and the figures", ("training.cli.episodes",)
    ),
    "plan": Entry("plan a scenario with the MILP expert and write the plan JSON", ("training.cli.planning",)),
    "validate": Entry(
        "check a scenario, or a plan for it, against the format's rules and list every violation",
        ("training.cli.planning",),
    ),
    "rollout": Entry(
        "run one episode in the physics env (a policy, or a saved plan with --plan) and print its figures",
        ("training.cli.episodes",),
    ),
    "evaluate-expert": Entry("success rate and speed of the expert in physics, per family", ("training.cli.episodes",)),
    "generate": Entry("generate a Minari dataset of episodes (resumable)", ("training.cli.data",)),
    "dataset": Entry("inspect, replay and render Minari datasets", ("training.cli.data",)),
    "train": Entry(
        "train a learned baseline (behaviour cloning, DAgger, MaskablePPO, ...) into a run folder",
        ("training.cli.train",),
    ),
    "benchmark": Entry(
        "evaluate policies against the MILP expert on a split or a folder of scenarios", ("training.cli.benchmark",)
    ),
    "references": Entry(
        "make or check the fixed expert references of the published splits", ("training.cli.benchmark",)
    ),
    "leaderboard": Entry(
        "merge benchmark result folders into one ranked table per split, with paired statistics",
        ("training.cli.leaderboard",),
    ),
    "compare": Entry(
        "compare two methods on the same scenarios: paired bootstrap and the sign over training seeds",
        ("training.cli.compare",),
    ),
    "reproduce": Entry(
        "the published table: expert data, every learned baseline per training seed, every split",
        ("training.cli.reproduce",),
    ),
}
"""The commands in the order ``fetchcarry --help`` lists them."""

MOVED_COMMANDS = {
    "bench": "fetchcarry bench moved out of the package in 0.2.0: from a checkout of the repository, "
    "run `python -m benchmarks --help` (speed benchmarks and studies)",
}
"""Commands that left ``fetchcarry``, and the message that says where they went (exit status 2)."""


def summary(name: str) -> str:
    """The one line of help of top-level command ``name`` (what its module passes to ``add_parser``)."""
    return COMMANDS[name].help


EXTRAS = {"minari": "train", "h5py": "train", "PIL": "train", "ray": "ray", "highspy": "dev"}
"""Optional packages by top-level module name, and the extra of ``pip install -e ".[EXTRA]"`` that brings each."""


def missing_extra(error: ModuleNotFoundError) -> str | None:
    """The message for a command that needs an optional package that is not installed, or None if it is not one."""
    package = (error.name or "").split(".")[0]
    if package not in EXTRAS:
        return None
    extra = EXTRAS[package]
    return f'this command needs {package}, which is not installed: pip install -e ".[{extra}]" (or ".[all]")'


class MissingExtraError(InputError):
    """A command needs an optional package that is not installed (exit 2, naming the extra that brings it)."""


def needing_extras(handler: Callable[..., int | None]) -> Callable[..., int | None]:
    """``handler``, with a missing optional package turned into a :class:`MissingExtraError` that names its extra."""

    def run(args: object) -> int | None:
        try:
            return handler(args)
        except ModuleNotFoundError as error:
            message = missing_extra(error)
            if message is None:
                raise
            raise MissingExtraError(message) from error

    return run


def selected(argv: list[str]) -> str | None:
    """The command ``argv`` runs (its first word, when that names one), or None (``--help``, nothing, a typo)."""
    return argv[0] if argv and argv[0] in COMMANDS else None
