"""The ``fetchcarry references`` command: make or check the fixed references of the published splits.

Exit statuses: 0 made (or, with ``--check``, every file agrees with its split and its
re-planned sample); 1 a file disagrees with sampling its split again, or a re-planned
reference with its record (``--check``); 2 bad input (an unknown split).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from training.cli.arguments import add_worker_options, non_negative_int, positive_int
from training.cli.commands import summary
from training.cli.exits import say
from training.cli.options import Command
from training.cli.text import echo
from training.data.generate import progress_bar
from training.evaluation.invariant import beaten
from training.evaluation.references import (
    FOLDER,
    FORMAT,
    REFERENCE_TIME_LIMIT,
    compute_references,
    digest_mismatches,
    load_references,
    merged_records,
    part_references,
    partial_version,
    replan_mismatches,
    replan_sample,
    write_references,
)
from training.evaluation.results import RESULTS, RESULTS_GZIP, read_results
from training.evaluation.splits import EvalScenario, Split, published_splits

REPLAN_SAMPLE = 2  # --check: proven references planned again per split version

REFERENCES_COMMAND = Command(
    name="references",
    help=summary("references"),
    description="Run the MILP expert once, with a generous planning limit, on every scenario of a split's dev "
    "and test parts, and write the split's reference file (every scenario's digest and the expert's cost, "
    "return, phases, pushes and proven status). The benchmark's cost ratio, SPL and score read these files, "
    "never a run's timing. --check samples every published split again and compares every digest, then plans a "
    "sample of proven references again and compares cost, return and status.",
    epilog="Exit status: 0 written (or every file agrees, or no episode beats a proven reference), 1 a file "
    "disagrees with its split or its re-planned sample (--check) or an episode beats a proven reference "
    "(--invariant), 2 bad input.",
)


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``references`` to the ``fetchcarry`` parser."""
    parser = REFERENCES_COMMAND.add(commands, run_references)
    versions = sorted({s.version for s in published_splits()})
    parser.add_argument(
        "--split",
        nargs="+",
        metavar="NAME",
        default=versions,
        help=f"split versions to make (default every one: {', '.join(versions)})",
    )
    parser.add_argument("--dev-episodes", type=positive_int, metavar="N", help="dev episodes (default the part's)")
    parser.add_argument("--test-episodes", type=positive_int, metavar="N", help="test episodes (default the part's)")
    parser.add_argument(
        "--time-limit",
        type=float,
        default=REFERENCE_TIME_LIMIT,
        metavar="S",
        help=f"seconds per planning call (default {REFERENCE_TIME_LIMIT:g})",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=FOLDER,
        metavar="DIR",
        help="folder of the reference files (default: the package's own)",
    )
    add_worker_options(parser)
    parser.add_argument(
        "--extend",
        action="store_true",
        help="keep the records of the existing file and of an interrupted run (same scenario, same --time-limit) "
        "and compute only the others",
    )
    parser.add_argument(
        "--check",
        action="store_true",
        help="only check the published files: every digest against its split, sampled again, and --sample proven "
        "references of each split planned again (cost, return, status, phases, pushes and deliveries compared)",
    )
    parser.add_argument(
        "--sample",
        type=non_negative_int,
        default=REPLAN_SAMPLE,
        metavar="N",
        help=f"--check: proven references planned again per split version (default {REPLAN_SAMPLE})",
    )
    parser.add_argument(
        "--invariant",
        nargs="+",
        type=Path,
        metavar="RESULTS",
        help="only check results files (results.json, results.json.gz) or benchmark folders against the invariant: "
        "no episode earns more than the proven reference on its scenario; lists every episode that does",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def run_references(args: argparse.Namespace) -> int:
    """``fetchcarry references``: 0 written or agreeing, 1 a disagreement (``--check``, ``--invariant``)."""
    if args.invariant:
        return _run_invariant(args.invariant)
    if args.check:
        return _run_check(args.sample, progress=not args.no_progress)
    episodes = {k: v for k, v in (("dev", args.dev_episodes), ("test", args.test_episodes)) if v}
    for version in dict.fromkeys(s.partition(":")[0] for s in args.split):
        _make_references(version, args, episodes)
    return 0


def _make_references(version: str, args: argparse.Namespace, episodes: dict[str, int]) -> None:
    """Compute and write ``version``'s references; an interrupted run keeps what finished in a partial file."""
    started = time.perf_counter()
    partial = partial_version(version)
    keep = None
    if args.extend:
        keep = merged_records(load_references(version, args.out), load_references(partial, args.out))
    try:
        content = compute_references(
            version,
            episodes=episodes,
            workers=args.workers,
            backend=args.backend,
            ray_address=args.ray_address,
            time_limit=args.time_limit,
            progress=not args.no_progress,
            keep=keep,
            checkpoint=lambda so_far: write_references(so_far, args.out, name=partial),
        )
    except KeyboardInterrupt:
        say(f"the finished references are kept in {args.out / partial}.json: run the same command with --extend")
        raise
    path = write_references(content, args.out)
    (args.out / f"{partial}.json").unlink(missing_ok=True)
    echo(f"{path}: {_summary(content)}, {time.perf_counter() - started:.0f} s")


def _run_check(sample: int, progress: bool) -> int:
    """``--check``: the digests of every published part, then ``sample`` proven references per version planned again."""
    splits = published_splits()
    problems = [line for split in splits for line in digest_mismatches(split)]
    echo(f"{sum(len(part_references(s)) for s in splits)} scenario digests checked, {len(problems)} differ")
    parts_of: dict[str, list[Split]] = {}
    for split in splits:
        content = load_references(split.version)
        if content is not None and content["format"] == FORMAT:  # a legacy file's task is not this planner's
            parts_of.setdefault(split.version, []).append(split)
    items = [item for parts in parts_of.values() for item in _spread(parts, sample)]
    replanned: list[str] = []
    with progress_bar(len(items), "references planned again", enabled=progress) as bar:
        for item in items:
            replanned.extend(replan_mismatches(item, load_references(item.split.partition(":")[0])["time_limit_s"]))
            bar.update(1)
    echo(f"{len(items)} proven references planned again, {len(replanned)} fields differ")
    problems.extend(replanned)
    for line in problems[:20]:
        echo(line)
    return 1 if problems else 0


def _spread(parts: list[Split], sample: int) -> list[EvalScenario]:
    """``sample`` proven references of one split version, spread over its parts (dev first)."""
    share, rest = divmod(sample, len(parts))
    return [item for k, part in enumerate(parts) for item in replan_sample(part, share + (k < rest))]


def _summary(content: dict) -> str:
    """``dev 100 (100 solved, 100 proven optimal, planning 12.3 s), test ...``."""
    parts = []
    for part, records in content["parts"].items():
        solved, proven = sum(r["success"] for r in records), sum(r["proven"] for r in records)
        planning = sum(r["planning_s"] for r in records)
        parts.append(f"{part} {len(records)} ({solved} solved, {proven} proven optimal, planning {planning:.1f} s)")
    return ", ".join(parts)


def _run_invariant(paths: list[Path]) -> int:
    """``--invariant``: the episodes of ``paths`` that earn more than a proven reference; 1 when there is one."""
    records = [record for path in paths for record in read_results(_results_file(path))]
    found, compared = beaten(records)
    for case in found[:20]:
        echo(
            f"{case.policy} {case.split} seed {case.seed}: return {case.episode_return:.3f} in {case.phases} steps "
            f"above the proven reference's {case.reference_return:.3f} in {case.reference_phases}"
        )
    if len(found) > 20:
        echo(f"... and {len(found) - 20} more")
    echo(f"{len(found)} of {compared} episodes with a proven reference earn more than it ({len(records)} records read)")
    return 1 if found else 0


def _results_file(path: Path) -> Path:
    """``path`` itself, or the results file of the benchmark folder ``path``."""
    if path.is_dir():
        for name in (RESULTS, RESULTS_GZIP):
            if (path / name).is_file():
                return path / name
    return path
