"""The ``fetchcarry reproduce`` command: the published table (every baseline, every split, N training seeds).

Exit statuses: 0 done (also when the folder already held the finished table); 2 bad
input (a folder made with another budget, a number below 1); 130 interrupted (what
finished is kept: the same command continues where it stopped).
"""

from __future__ import annotations

import argparse
import sys

from training.cli.arguments import positive_int
from training.cli.commands import summary
from training.cli.exits import INTERRUPTED, ignore_unraisable, say
from training.cli.text import echo
from training.data.generate import BACKENDS
from training.reproduce import BUDGETS, FULL, reproduce
from training.reproduce.publish import publish

FULL_ESTIMATE = "2 h 42 min measured for three seeds on 2 shared cores, 3.5 CPU hours"
# Measured (docs/benchmarks/learning.md, "Its time"): the table of 2026-12-02/03, seven test parts at up to 300
# episodes; about 1 h 45 min on two idle cores by its CPU seconds.


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``reproduce`` to the ``fetchcarry`` parser."""
    parser = commands.add_parser(
        "reproduce",
        help=summary("reproduce"),
        description="Make the published table in one folder: (1) the MILP expert's episodes on the training "
        "family (basic, push, corridor or multi-2) as a candidate-phase Minari dataset under DIR/datasets; "
        "(2) per training seed, BC with the flat MLP and the set encoder, DAgger, DAgger aimed at push and "
        "multi-2 from the whole dataset (dagger-aimed), MaskablePPO from scratch and from the BC weights, and BC "
        "on fewer demonstrations, each a run folder in DIR/runs, then the ensemble of the seeds' dagger-aimed "
        "runs; (3) the benchmark "
        "of expert, random, random-phases, greedy and every run on the test parts of the splits iid, "
        "more-objects, layouts, push-required and the graded worlds objects (1-12 objects), apartment and "
        "perturbed (DIR/benchmark/SPLIT; every learner is trained at the capacity objects=12,clutter=12, which "
        "holds them all); (4) DIR/summary.md (per split, each baseline's mean over the "
        "seeds with its range, success pooled over seeds with a 95 % bootstrap interval over scenarios; the "
        "commit of the code that made it), DIR/results.json and plots. --publish DEST copies the table (its "
        "records as results.json.gz), every run's config and metrics, and the best run's weights of each learner "
        "into DEST (refused above 50 MB). "
        f"Every stage is skipped when complete. The full budget took {FULL_ESTIMATE}, with 2 workers.",
        epilog="Exit status: 0 done, 2 bad input (another budget in DIR, a bad number), 130 interrupted (what "
        "finished is kept: run the same command again to continue).",
    )
    parser.add_argument("--out", required=True, metavar="DIR", help="the reproduction's folder")
    parser.add_argument(
        "--seeds", type=positive_int, default=3, metavar="N", help="training seeds 0 .. N-1 (default 3)"
    )
    parser.add_argument(
        "--budget",
        choices=tuple(BUDGETS),
        default=FULL.name,
        help="full: the published budget (default); smoke: every stage at a toy size, a few minutes",
    )
    parser.add_argument(
        "--workers",
        type=positive_int,
        default=2,
        metavar="W",
        help="processes for expert episodes and benchmark episodes, and training runs at a time (default 2)",
    )
    parser.add_argument(
        "--backend",
        choices=BACKENDS,
        default="process",
        help="a local process pool (default) or Ray (optional extra: pip install ray): the expert episodes, each "
        "training run (one Ray task) and the benchmark's episodes, the same records either way",
    )
    parser.add_argument(
        "--ray-address",
        metavar="ADDR",
        help="a Ray cluster to join (default: start a local one of W CPUs); DIR and --datasets must be on a file "
        "system every node sees",
    )
    parser.add_argument(
        "--datasets", metavar="PATH", help="the Minari datasets folder for the expert dataset (default DIR/datasets)"
    )
    parser.add_argument(
        "--publish",
        metavar="DEST",
        help="then copy summary.md, results.json, plots, every run's config.json and metrics.csv and each learner's "
        "best run's model.pt into DEST (a folder of the repository; refused above 50 MB)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bars (the stage lines stay)")
    parser.set_defaults(handler=run_reproduce)


def run_reproduce(args: argparse.Namespace) -> int:
    """``fetchcarry reproduce``: 0 done, 130 interrupted.

    Bad input is a ``ReproduceError`` or a ``BenchmarkError`` (both ``InputError``: exit 2);
    any other error is a bug (exit 3 with a crash report).
    """
    try:
        summary = reproduce(args.out, seeds=args.seeds, budget=BUDGETS[args.budget], workers=args.workers,
                            backend=args.backend, ray_address=args.ray_address, progress=not args.no_progress,
                            datasets=args.datasets, say=echo)  # fmt: skip
    except KeyboardInterrupt:
        sys.unraisablehook = ignore_unraisable  # see training.cli.exits.run_command
        say(f"interrupted: what finished is kept in {args.out}; run the same command again to continue")
        return INTERRUPTED
    echo(f"the published table: {summary}")
    if args.publish:
        copied = publish(args.out, args.publish)
        echo(f"published {copied['files']} files ({copied['bytes'] / 2**20:.1f} MB) to {args.publish}")
    return 0
