"""The ``fetchcarry benchmark`` command: learned policies against the MILP expert on a split or a folder.

With ``--check RESULTS.json`` it runs the episodes of the file's records of the given
policies again and says how many came out identical, timings aside
(:mod:`training.evaluation.recheck`).

Exit statuses: 0 done (with ``--check``: every record identical); 1 (``--check``) a
record came out differently; 2 bad input (an unknown policy or split, a missing or broken run
folder, an unusable scenario file, a ``results.json`` that breaks its schema, another
benchmark writing to the same ``OUT_DIR``); 130 interrupted (the finished episodes are kept in
``OUT_DIR/results.json``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import asdict
from pathlib import Path

from training.cli import references
from training.cli.arguments import add_worker_options, capacity_text, positive_int
from training.cli.commands import summary
from training.cli.episodes import add_obs_mode_argument
from training.cli.exits import INTERRUPTED, ignore_unraisable, say
from training.cli.text import echo
from training.errors import BenchmarkError
from training.evaluation.recheck import recheck
from training.evaluation.runner import RESULTS, SUMMARY, run_benchmark
from training.evaluation.splits import SPLITS, get_split


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``benchmark`` to the ``fetchcarry`` parser."""
    parser = commands.add_parser(
        "benchmark",
        help=summary("benchmark"),
        description=_description(),
        epilog="Exit status: 0 done (--check: every record identical), 1 (--check) a record came out differently, "
        "2 bad input (unknown policy or split, missing run folder, unusable "
        "scenario file, a results.json that breaks its schema, another benchmark writing to OUT_DIR), "
        "130 interrupted (the finished episodes are kept in results.json), 143 stopped by SIGTERM (the same).",
    )
    parser.add_argument(
        "--policies",
        nargs="+",
        required=True,
        metavar="POLICY",
        help="each one of: expert, random, random-phases, greedy, expert-phases (where installed); a run folder "
        "(as fetchcarry train writes); or package.module:factory, your own factory that is called with the env "
        "and returns a policy (docs/protocol.md), found from the working folder first, then the installed "
        "packages: naming it imports and runs your code, so trust it as you would a script you run",
    )
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--split",
        nargs="+",
        metavar="NAME",
        help="one or more split names, e.g. iid or iid-v0 (the newest version if none is given); with --check, "
        "only the records of these splits",
    )
    where.add_argument(
        "--scenarios",
        metavar="DIR",
        help="a folder of scenario files (*.json) whose areas fit inside the families' extent",
    )
    parser.add_argument(
        "--check",
        metavar="RESULTS.json",
        help="instead of a benchmark: run the episodes of this file's records of the given policies again (a run "
        "folder's records are those of its folder's name) and report how many are identical apart from the timing "
        "fields (decision_ms, mask_ms, step_ms); exit 0 only when all are, 1 otherwise",
    )
    parser.add_argument(
        "--episodes", type=positive_int, metavar="N", help="episodes (default: the split's 100, or every file)"
    )
    add_worker_options(parser)
    parser.add_argument(
        "--out", metavar="OUT_DIR", help="folder for results.json, summary.md, plots (required, but with --check)"
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument(
        "--resume",
        action="store_true",
        help="keep the episodes already in OUT_DIR/results.json and run the others (a scenario whose content "
        "changed runs again); its records of other policies and splits stay (one folder can grow a policy at a time)",
    )
    parser.add_argument("--json", action="store_true", help="print the table's rows as one JSON list")
    add_obs_mode_argument(
        parser,
        "the observation the policies get (default: state; a run folder of an image network gets its own, "
        "and another mode given for it is refused)",
        default=None,
    )
    parser.add_argument(
        "--capacity",
        type=capacity_text,
        metavar="K=N,...",
        help="the observation's slots every policy acts with, e.g. objects=8 (the other counts the default's); "
        "a set-encoder run acts at any capacity, a flat network only at its own (refused otherwise); default: "
        "each run folder's own where it holds the split's scenarios, else the split's",
    )
    parser.set_defaults(handler=run_benchmark_command)
    references.register(commands)


def _description() -> str:
    """``fetchcarry benchmark --help``'s description: what it measures and writes, and the splits."""
    names = dict.fromkeys(s.base_name for s in SPLITS.values())  # each split once, described by its newest version
    splits = ", ".join(f"{name} ({get_split(name).description})" for name in names)
    return (
        "Run every policy on the same scenarios and compare it with the MILP expert on each: "
        "success with a 95 % Wilson interval, objects delivered, cost ratio to the expert, a cost-weighted "
        "success (SPL), phases and pushes, invalid actions, contacts, time per decision, and the normalised "
        "score 100 x sum(R - F) / sum(R_reference - F), F the return of doing nothing (0: doing nothing, 100: "
        "the proven reference; no failure scores above a success). The expert and random policies always run "
        "as references. Writes OUT_DIR/results.json (one record per policy and episode, rewritten as episodes "
        "finish), OUT_DIR/summary.md (the table, then success and cost ratio per scenario source) and "
        "OUT_DIR/splits.png. "
        f"Splits: {splits}. Evaluation seeds start at 10^9, so they never meet training seeds."
    )


def run_benchmark_command(args: argparse.Namespace) -> int:
    """``fetchcarry benchmark``: 0 done, 130 interrupted (bad input is a ``BenchmarkError``, an ``InputError``)."""
    if args.check is not None:
        return run_check(args)
    if args.out is None or (args.split is None and args.scenarios is None):
        raise BenchmarkError("give --out and one of --split and --scenarios (or --check RESULTS.json)")
    try:
        report = run_benchmark(
            args.policies,
            out=args.out,
            split=args.split,
            scenarios=args.scenarios,
            episodes=args.episodes,
            workers=args.workers,
            backend=args.backend,
            ray_address=args.ray_address,
            progress=not args.no_progress,
            resume=args.resume,
            obs_mode=args.obs_mode,
            capacity=args.capacity,
        )
    except KeyboardInterrupt:
        sys.unraisablehook = ignore_unraisable  # see training.cli.exits.run_command
        results = Path(args.out) / RESULTS
        if results.is_file():
            say(f"interrupted: the finished episodes are in {results}; add --resume to finish them")
        else:
            say(f"interrupted before any episode finished: nothing was written to {results}")
        return INTERRUPTED
    if args.json:
        print(json.dumps([_json_row(asdict(row)) for row in report.rows], indent=1))
        return 0
    echo((report.out / SUMMARY).read_text())
    echo(f"wrote {len(report.records)} records to {report.out / RESULTS}")
    return 0


def _json_row(row: dict) -> dict:
    """A row with ``null`` for figures that do not exist (nan: a cost ratio without a success)."""
    return {k: None if isinstance(v, float) and math.isnan(v) else v for k, v in row.items()}


def run_check(args: argparse.Namespace) -> int:
    """``fetchcarry benchmark --check RESULTS.json``: 0 every record identical (timings aside), 1 not, 130 stopped."""
    options = {"--scenarios": args.scenarios, "--episodes": args.episodes, "--resume": args.resume,
               "--json": args.json, "--out": args.out}  # fmt: skip
    given = [flag for flag, value in options.items() if value]
    if given:
        raise BenchmarkError(f"--check re-runs the file's own episodes and writes nothing: leave out {given[0]}")
    try:
        report = recheck(args.check, args.policies, splits=args.split, workers=args.workers, backend=args.backend,
                         ray_address=args.ray_address, obs_mode=args.obs_mode, capacity=args.capacity,
                         progress=not args.no_progress)  # fmt: skip
    except KeyboardInterrupt:
        sys.unraisablehook = ignore_unraisable  # see training.cli.exits.run_command
        say("interrupted: nothing was compared")
        return INTERRUPTED
    for mismatch in report.mismatches:
        echo(mismatch.line())
    echo(report.line())
    return 0 if report.all_identical else 1
