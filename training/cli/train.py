"""The training commands: ``fetchcarry train KIND``, one per registered learner (bc, dagger, ppo, ensemble, ...).

Each command is made from its learner (:mod:`training.learners.registry`): every option
field of the learner's options dataclass (:func:`training.learners.options.option`)
becomes a ``--flag`` with its type, default, choices and help, and the run options
(``--out``; ``--resume`` and ``--no-progress`` for a resumable learner; ``--workers`` and
``--backend`` for one that labels on the worker pool) come from :func:`add_run_options`.
Each writes a run folder (``config.json``, ``metrics.csv``, ``checkpoint.pt``,
``model.pt``; see :mod:`training.learners.runs`) that ``fetchcarry benchmark`` and
``fetchcarry rollout --policy RUN_DIR`` take, and ``training.load_policy(path)`` loads.

Exit statuses: 0 trained (also when the run folder already held the complete run);
2 bad input (also training data of the benchmark's evaluation seeds or split scenarios
without ``--allow-evaluation-seeds``: :mod:`training.cli.refusals`); 130 interrupted (the
last checkpoint is kept: the same command with ``--resume`` finishes the run).
"""

from __future__ import annotations

import argparse
import sys
import typing
from collections.abc import Callable
from dataclasses import MISSING, Field, fields
from pathlib import Path
from types import NoneType, UnionType
from typing import Any

from fetchcarry_env.errors import InputError
from training.cli.arguments import positive_float, positive_int, whole_number
from training.cli.commands import summary
from training.cli.exits import INTERRUPTED, ignore_unraisable, say
from training.cli.refusals import add_refusal_option, refuse_evaluation_data
from training.cli.text import echo
from training.learners import registry

RUN_EPILOG = (
    "The run folder holds config.json (the kind, the interface and every option), metrics.csv, checkpoint.pt and, "
    "once finished, model.pt. Exit status: 0 trained, 2 bad input, 130 interrupted (the last checkpoint is kept: "
    "run the same command with --resume to finish)."
)
WRITE_EPILOG = "Exit status: 0 written, 2 bad input (an OUT that holds a run already), 130 interrupted."
DEST = "options."  # the prefix of the parsed options' names (a field "out" cannot clash with --out)


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``train KIND`` for every registered learner to the ``fetchcarry`` parser."""
    parser = commands.add_parser(
        "train",
        help=summary("train"),
        description="Train a learned policy on the candidate-phase interface (FetchCarryPushPhases-v0) into a "
        "run folder. Deterministic on CPU for one --seed.",
    )
    kinds = parser.add_subparsers(dest="kind", metavar="KIND", required=True)
    for learner in registry.learners():
        epilog = learner.epilog or (RUN_EPILOG if learner.resumable else WRITE_EPILOG)
        command = kinds.add_parser(learner.kind, help=learner.help, description=learner.description, epilog=epilog)
        add_options(command, learner.options)
        add_run_options(command, resumable=learner.resumable, pool=learner.pool)
        if learner.refuse is not None:
            add_refusal_option(command)
        command.set_defaults(handler=run_train)


def add_run_options(parser: argparse.ArgumentParser, *, resumable: bool, pool: bool) -> None:
    """Where and how a run trains (not in ``config.json``'s options): ``--out`` and what else the learner takes."""
    if pool:
        parser.add_argument(
            "--workers", type=positive_int, default=1, metavar="W", help="labelling workers (default 1)"
        )
        parser.add_argument(
            "--backend", choices=("process", "ray"), default="process", help="a local process pool (default) or Ray"
        )
    parser.add_argument("--out", required=True, metavar="RUN_DIR", help="the run folder to write")
    if resumable:
        parser.add_argument("--resume", action="store_true", help="finish the interrupted run in RUN_DIR")
        parser.add_argument("--no-progress", action="store_true", help="no progress bar")


# ---------------------------------------------------------------------------- options from a dataclass
def add_options(parser: argparse.ArgumentParser, settings: type, defaults: Any = None, prefix: str = "",
                omit: tuple[str, ...] = ()) -> None:  # fmt: skip
    """A ``--flag`` per option field of the dataclass ``settings`` (``defaults``: an instance whose values show)."""
    hints = typing.get_type_hints(settings)
    for item in fields(settings):
        if item.name in omit:
            continue
        default = _default(item) if defaults is None else getattr(defaults, item.name)
        if item.metadata.get("nested"):
            add_options(parser, hints[item.name], default, f"{prefix}{item.name}.", item.metadata["omit"])
        elif "help" in item.metadata:
            flag, arguments = _argument(item, hints[item.name], default)
            parser.add_argument(flag, dest=f"{DEST}{prefix}{item.name}", **arguments)


def read_options(settings: type, parsed: dict[str, Any], defaults: Any = None, prefix: str = "") -> Any:
    """The ``settings`` dataclass built from the parsed options (``vars(args)``); its checks raise InputError."""
    values = {}
    for item in fields(settings):
        default = _default(item) if defaults is None else getattr(defaults, item.name)
        name = f"{DEST}{prefix}{item.name}"
        if item.metadata.get("nested"):
            values[item.name] = read_options(typing.get_type_hints(settings)[item.name], parsed, default,
                                             f"{prefix}{item.name}.")  # fmt: skip
        elif name in parsed:
            values[item.name] = parsed[name]
        elif default is not MISSING:
            values[item.name] = default  # not an option, or omitted from this command: its default
    return settings(**values)


def _default(item: Field) -> Any:
    return item.default_factory() if item.default_factory is not MISSING else item.default


def _argument(item: Field, hint: Any, default: Any) -> tuple[str, dict[str, Any]]:
    """The flag and ``add_argument`` keywords of option field ``item`` (annotation ``hint``)."""
    meta = item.metadata
    flag = "--" + item.name.replace("_", "-")
    shown = f"{default:g}" if isinstance(default, float) else default
    arguments: dict[str, Any] = {"help": meta["help"].format(default=shown)}
    value_type = _value_type(hint)
    if value_type is bool:
        arguments["action"] = "store_false" if default else "store_true"
        return ("--no-" + item.name.replace("_", "-") if default else flag), arguments
    if default is MISSING:
        arguments["required"] = True
    else:
        arguments["default"] = default
    if meta["parse"] is not None:
        arguments["type"] = _reader(meta["parse"])
    elif value_type is int:
        arguments["type"] = positive_int if meta["positive"] else whole_number
    elif value_type is float:
        arguments["type"] = positive_float if meta["positive"] else float
    elif value_type is not str:
        raise TypeError(f"option {item.name}: no command-line reading of {hint!r}; give parse=")
    for key in ("choices", "nargs"):
        if meta[key] is not None:
            arguments[key] = meta[key]
    metavar = meta["metavar"] or ("N" if value_type is int else None)
    if meta["choices"] is None and metavar is not None:
        arguments["metavar"] = metavar
    return flag, arguments


def _value_type(hint: Any) -> Any:
    """``int`` of ``int | None``; ``str`` of ``tuple[str, ...]`` (a field of several values); else ``hint``."""
    if isinstance(hint, UnionType):
        (hint,) = [part for part in typing.get_args(hint) if part is not NoneType]
    if typing.get_origin(hint) is tuple:
        return typing.get_args(hint)[0]
    return hint


def _reader(parse: Callable[[str], Any]) -> Callable[[str], Any]:
    """``parse`` as an argparse type: its :class:`InputError` becomes argparse's message (exit 2)."""

    def read(text: str) -> Any:
        try:
            return parse(text)
        except InputError as error:
            raise argparse.ArgumentTypeError(str(error)) from None

    read.__name__ = parse.__name__
    return read


# ---------------------------------------------------------------------------- running
def run_train(args: argparse.Namespace) -> int:
    """Train the options of ``args`` with its learner; print what was trained (Ctrl-C keeps the checkpoint)."""
    learner = registry.get(args.kind)
    options = read_options(learner.options, vars(args))
    refuse_evaluation_data(learner, options, getattr(args, "allow_evaluation_seeds", False))
    try:
        registry.train(learner.kind, options, args.out, resume=getattr(args, "resume", False),
                       progress=not getattr(args, "no_progress", False), workers=getattr(args, "workers", 1),
                       backend=getattr(args, "backend", "process"))  # fmt: skip
    except KeyboardInterrupt:
        if not learner.resumable:
            raise
        sys.unraisablehook = ignore_unraisable
        say(f"interrupted: the last checkpoint in {args.out} is kept; add --resume to the same command to finish")
        return INTERRUPTED
    echo(learner.describe(options, _metrics(args.out), args.out))
    return 0


def _metrics(out: str) -> list[dict[str, float]]:
    from training.learners.runs import METRICS_FILE, read_metrics  # torch: loaded by the training already

    return read_metrics(out) if (Path(out) / METRICS_FILE).is_file() else []
