"""The ``fetchcarry leaderboard`` command: result folders merged into one ranked table per split.

Exit statuses: 0 printed; 2 bad input (a folder without ``results.json``, a file that
breaks its schema or its caps or holds an episode twice (docs/results-format.md),
results of different split versions or references, a method in two folders).
"""

from __future__ import annotations

import argparse
import json

from training.cli.commands import summary
from training.cli.options import Command
from training.cli.text import echo
from training.evaluation.across import across_markdown, across_splits
from training.evaluation.leaderboard import leaderboard, leaderboard_markdown, merge_folders

LEADERBOARD_COMMAND = Command(
    name="leaderboard",
    help=summary("leaderboard"),
    description="Read DIR/results.json of every folder (fetchcarry benchmark --out folders, anyone's), check that "
    "they are comparable (one version of each split, the same fixed references, no method in two folders; "
    "expert, random, random-phases and greedy come from the first folder that has them) and print, per split, "
    "the methods (training seeds NAME-sK pooled) ranked by success then SPL, with intervals clustered by "
    "scenario and each method's paired difference in success with the first (bootstrap over the scenarios "
    "both ran, and the sign over training seeds); with two splits or more, the view across them: IQM of success "
    "with a stratified-bootstrap interval, probability of improvement over greedy and the performance profile "
    "(Agarwal et al. 2021).",
    epilog="Exit status: 0 printed, 2 bad input (no results.json, a file that breaks its schema or caps or holds an "
    "episode twice: docs/results-format.md, different split "
    "versions or references, a method in two folders).",
)


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``leaderboard`` to the ``fetchcarry`` parser."""
    parser = LEADERBOARD_COMMAND.add(commands, run_leaderboard)
    parser.add_argument("folders", nargs="+", metavar="DIR", help="benchmark output folders (each with results.json)")
    parser.add_argument("--split", nargs="+", metavar="NAME", help="only these splits (full names, e.g. iid-v1:test)")
    parser.add_argument("--json", action="store_true", help="print the ranked entries as one JSON object per split")


def run_leaderboard(args: argparse.Namespace) -> int:
    """``fetchcarry leaderboard``: 0 printed (bad input is an ``InputError``: exit 2)."""
    records = merge_folders(args.folders)
    if args.split:
        records = [r for r in records if r["split"] in args.split]
    board = leaderboard(records)
    if args.json:
        print(json.dumps({split: [e.to_dict() for e in entries] for split, entries in board.items()}, indent=1))
        return 0
    echo(leaderboard_markdown(board))
    across = across_splits(records)
    if across is not None:
        echo("\n".join(across_markdown(across)))
    return 0
