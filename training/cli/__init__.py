"""The ``fetchcarry`` command line: every command's options, handlers and printed output.

:mod:`~training.cli.commands` lists every command with its help line and its modules:
``fetchcarry --help`` imports none of them, ``fetchcarry COMMAND`` only its own. One
module per group of commands (:mod:`~training.cli.planning`: ``plan``,
``validate``; :mod:`~training.cli.episodes`: ``rollout``, ``demo``,
``evaluate-expert``; :mod:`~training.cli.data`: ``generate``, ``dataset``;
:mod:`~training.cli.benchmark`: ``benchmark``; :mod:`~training.cli.train`: ``train KIND``, one per
registered learner;
:mod:`~training.cli.reproduce`: ``reproduce``; :mod:`~training.cli.leaderboard`: ``leaderboard``;
:mod:`~training.cli.compare`: ``compare``; ``references`` with ``benchmark``), each with a
``register(commands)`` function. The benchmarks that print figures (speed, studies) are
not part of the package: ``python -m benchmarks`` runs them from a checkout. Library code never speaks of flags or exit
statuses: this package turns its exceptions into them (:mod:`~training.cli.exits`).

Exit statuses: 0 success, 1 a negative answer (no plan, an invalid plan, a failed
episode), 2 bad input (a short message, never a traceback), 3 an unexpected internal
error (a short message and the path of the full report), 130 interrupted (Ctrl-C), 143
stopped by SIGTERM (as Ctrl-C).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from training.cli.commands import COMMANDS, MOVED_COMMANDS, missing_extra, needing_extras, selected
from training.cli.exits import BAD_INPUT, INTERRUPTED, run_command, say

DESCRIPTION = (
    "Fetch-and-carry with push-aside: plan with the MILP expert, run episodes in PyBullet, build datasets and "
    "benchmarks. 'fetchcarry COMMAND --help' explains a command."
)
EPILOG = (
    "Exit status: 0 success, 1 a negative answer (no plan, an invalid plan, a failed episode), 2 bad input, "
    "3 an internal error (the message says where the full report is), 130 interrupted (Ctrl-C), 143 stopped by "
    "SIGTERM (what finished is kept, as on Ctrl-C)."
)


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The ``fetchcarry`` parser: every command's options when ``argv`` is None, else only those of its command.

    With ``argv``, only the modules of the command it runs are imported (none for ``--help``); the
    other commands are listed by name and help line (:mod:`training.cli.commands`), so that a
    command starts without importing what the others need.
    """
    parser = argparse.ArgumentParser(prog="fetchcarry", description=DESCRIPTION, epilog=EPILOG)
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    chosen = None if argv is None else selected(list(argv))
    loaded: set[str] = set()
    for name, entry in COMMANDS.items():
        if argv is None or name == chosen:
            for module in (m for m in entry.modules if m not in loaded):
                loaded.add(module)
                importlib.import_module(module).register(commands)
    for name, entry in COMMANDS.items():  # the other commands, listed by name: their modules stay unloaded
        if name not in commands.choices:
            commands.add_parser(name, help=entry.help, add_help=False)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``fetchcarry argv...`` and return its exit status (argparse's own errors exit 2 by ``SystemExit``)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] in MOVED_COMMANDS:
        say(MOVED_COMMANDS[argv[0]])
        return BAD_INPUT
    try:
        args = build_parser(argv).parse_args(argv)
    except KeyboardInterrupt:
        say("interrupted")
        return INTERRUPTED
    except ModuleNotFoundError as error:
        message = missing_extra(error)
        if message is None:
            raise
        say(message)
        return BAD_INPUT
    return run_command(needing_extras(args.handler), args)
