"""The ``fetchcarry`` command line.

Each package contributes its commands through a ``register(commands, bench)`` function
in its ``commands`` module; this module only wires them together and turns bad input
into a one-line message and exit status 2 (never a traceback).

Exit statuses: 0 success, 1 a negative answer (no plan, an invalid plan, a failed
episode), 2 bad input.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
from collections.abc import Sequence

from expert.plans import PlanFormatError
from fetchcarry_env.errors import UsageError
from fetchcarry_env.scenario import ScenarioError

COMMAND_MODULES = ("fetchcarry_env.commands", "expert.commands", "training.commands")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fetchcarry",
        description="Fetch-and-carry with push-aside: plan with the MILP expert, run episodes in PyBullet, "
        "build datasets and benchmarks.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    bench_parser = commands.add_parser(
        "bench", help="measure speed: env steps, planner times", description="Benchmarks that print figures."
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
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except (ScenarioError, PlanFormatError) as error:
        print(f"fetchcarry: {error}", file=sys.stderr)
    except (UsageError, FileNotFoundError, IsADirectoryError, PermissionError) as error:
        print(f"fetchcarry: {error}", file=sys.stderr)
    except json.JSONDecodeError as error:
        print(f"fetchcarry: not valid JSON: {error}", file=sys.stderr)
    except KeyboardInterrupt:
        print("fetchcarry: interrupted", file=sys.stderr)
        return 130
    return 2


if __name__ == "__main__":
    sys.exit(main())
