"""The ``fetchcarry`` command line: every command's options, handlers and printed output.

One module per group of commands (:mod:`~training.cli.planning`: ``plan``,
``validate``; :mod:`~training.cli.episodes`: ``rollout``, ``demo``,
``evaluate-expert``; :mod:`~training.cli.data`: ``generate``, ``dataset``;
:mod:`~training.cli.bench`: ``bench env|planner|generate|phases|projection``; :mod:`~training.cli.benchmark`:
``benchmark``; :mod:`~training.cli.train`: ``train KIND``, one per registered learner; :mod:`~training.cli.checks`:
``bench learned|learning-checks``;
:mod:`~training.cli.reproduce`: ``reproduce``; :mod:`~training.cli.leaderboard`: ``leaderboard``;
:mod:`~training.cli.compare`: ``compare``; ``references`` with ``benchmark``), each with a
``register(commands, bench)`` function. Library code never speaks of flags or exit
statuses: this package turns its exceptions into them (:mod:`~training.cli.exits`).

Exit statuses: 0 success, 1 a negative answer (no plan, an invalid plan, a failed
episode), 2 bad input (a short message, never a traceback), 3 an unexpected internal
error (a short message and the path of the full report), 130 interrupted (Ctrl-C).
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Sequence

from training.cli.exits import INTERRUPTED, run_command, say

COMMAND_MODULES = (
    "training.cli.planning",
    "training.cli.episodes",
    "training.cli.data",
    "training.cli.bench",
    "training.cli.benchmark",
    "training.cli.train",
    "training.cli.checks",
    "training.cli.reproduce",
    "training.cli.leaderboard",
    "training.cli.compare",
)
"""Modules that add commands; a module that is not installed (an optional part) is skipped."""


def build_parser() -> argparse.ArgumentParser:
    """The ``fetchcarry`` parser with every command."""
    parser = argparse.ArgumentParser(
        prog="fetchcarry",
        description="Fetch-and-carry with push-aside: plan with the MILP expert, run episodes in PyBullet, "
        "build datasets and benchmarks.",
        epilog="Exit status: 0 success, 1 a negative answer (no plan, an invalid plan, a failed episode), "
        "2 bad input, 3 an internal error (the message says where the full report is), 130 interrupted.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    bench_parser = commands.add_parser(
        "bench",
        help="measure speed: env steps, planner times, dataset generation",
        description="Benchmarks that print figures.",
    )
    bench = bench_parser.add_subparsers(dest="bench", metavar="WHAT", required=True)
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as error:
            if error.name != name:
                raise
            continue
        module.register(commands, bench)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``fetchcarry argv...`` and return its exit status (argparse's own errors exit 2 by ``SystemExit``)."""
    try:
        args = build_parser().parse_args(argv)
    except KeyboardInterrupt:
        say("interrupted")
        return INTERRUPTED
    return run_command(args.handler, args)
