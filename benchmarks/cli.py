"""``python -m benchmarks WHAT ...``: the speed benchmarks and the studies that print figures.

The same conventions as ``fetchcarry`` (its exit statuses, Ctrl-C keeps what finished):
the speed benchmarks come from :mod:`benchmarks.speed.commands`, the studies from
:mod:`benchmarks.studies.commands`.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from benchmarks.speed import commands as speed_commands
from benchmarks.studies import commands as study_commands
from training.cli.exits import run_command

DESCRIPTION = (
    "Benchmarks that print figures, run from a checkout of the repository: the speed of the env, the planner "
    "and dataset generation (env, planner, anytime, push, generate, phases, ppo) and studies (learned, "
    "learning-checks, projection). 'python -m benchmarks WHAT --help' explains one. Evaluating policies "
    "against the expert on the published splits is 'fetchcarry benchmark'."
)
EPILOG = "Exit status: 0 measured, 1 a goal missed (with --strict) or an invalid plan, 2 bad input, 130 interrupted."


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``python -m benchmarks``: every benchmark and study."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=DESCRIPTION, epilog=EPILOG)
    subcommands = parser.add_subparsers(dest="what", metavar="WHAT", required=True)
    speed_commands.register(subcommands)
    study_commands.register(subcommands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``python -m benchmarks argv...`` and return its exit status."""
    args = build_parser().parse_args(argv)
    return run_command(args.handler, args)
