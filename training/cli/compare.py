"""The ``fetchcarry compare`` command: two methods paired on the same scenarios.

Exit statuses: 0 printed; 2 bad input (a folder without ``results.json``, a file that
breaks its schema or its caps or holds an episode twice (docs/results-format.md), a
method with no records on a split, two methods sharing no scenario).
"""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import asdict

from training.cli.commands import summary
from training.cli.options import Command
from training.cli.text import echo
from training.evaluation.compare import compare_methods, methods_by_split
from training.evaluation.leaderboard import merge_folders

COMPARE_COMMAND = Command(
    name="compare",
    help=summary("compare"),
    description="Per split that both methods ran, the difference A - B on the scenarios both ran (same seed and "
    "scenario digest): success (per-scenario success rate over the training seeds, mean difference with a 95 % "
    "paired bootstrap interval over scenarios), travel cost in metres (on the scenarios both solved), and the sign "
    "of the success difference over training seeds with its two-sided sign-test p-value. A method is a policy "
    "label with its training seeds NAME-sK pooled (bc-mlp for bc-mlp-s0, bc-mlp-s1, ...).",
    epilog="Exit status: 0 printed, 2 bad input (no results.json, a file that breaks its schema or caps or holds an "
    "episode twice: docs/results-format.md, an unknown method, no shared scenario).",
)


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``compare`` to the ``fetchcarry`` parser."""
    parser = COMPARE_COMMAND.add(commands, run_compare)
    parser.add_argument("a", metavar="A", help="a method (policy label, seeds pooled), e.g. dagger")
    parser.add_argument("b", metavar="B", help="the method to compare it with, e.g. bc-mlp")
    parser.add_argument(
        "--results",
        nargs="+",
        required=True,
        metavar="DIR",
        help="benchmark output folders holding both methods (merged as fetchcarry leaderboard does)",
    )
    parser.add_argument("--split", nargs="+", metavar="NAME", help="only these splits (default: every split of both)")
    parser.add_argument("--json", action="store_true", help="print the comparisons as one JSON list")


def run_compare(args: argparse.Namespace) -> int:
    """``fetchcarry compare A B``: 0 printed (bad input is an ``InputError``: exit 2)."""
    table = methods_by_split(merge_folders(args.results))  # one pass: split -> method -> records
    splits = args.split or [s for s, methods in table.items() if args.a in methods and args.b in methods]
    if not splits:
        splits = list(table)[:1]  # compare_methods() names what is missing
    results = [compare_methods(table.get(split, {}), args.a, args.b, split) for split in splits]
    if args.json:
        rows = [
            {k: None if isinstance(v, float) and math.isnan(v) else v for k, v in asdict(c).items()} for c in results
        ]
        print(json.dumps(rows, indent=1))
    else:
        for comparison in results:
            echo(comparison.line())
    return 0
