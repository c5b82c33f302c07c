"""``fetchcarry leaderboard``: result folders merged into one ranked table per split, with paired statistics.

Each folder is a ``fetchcarry benchmark --out`` folder (its ``results.json``, checked
against its schema). Folders are merged only when they are comparable:

- one version of each split (``iid-v0`` and ``iid-v1:test`` never meet in one table),
- one reference per split: every record's ``references`` (the digest of the fixed
  references its cost ratio was read from, or ``null`` for a run's own expert) agrees,
- one set of records per method: a learned method in two folders is refused (name
  runs apart); the reference policies (``expert``, ``random``, ``random-phases``,
  ``greedy``) are taken from the first folder that has them.

Per split, methods (training seeds pooled, :func:`training.evaluation.compare.method_of`)
are ranked by success, then SPL, on the scenarios every method ran (same seed and
digest): a method's episodes on other scenarios are left out of its row and counted in
``left_out`` (the table says so), and a split where no scenario is shared is refused.
Each row gives the paired comparison with the row ranked first
(:func:`training.evaluation.compare.compare`) on those scenarios.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from training.errors import BenchmarkError
from training.evaluation.compare import Comparison, compare_methods, grouped, method_of, pooled
from training.evaluation.metrics import Row, summarise
from training.evaluation.report import legend
from training.evaluation.results import RESULTS, read_results, results_file
from training.evaluation.splits import SPLITS

SHARED = ("expert", "random", "random-phases", "greedy")  # references every folder may hold


class LeaderboardError(BenchmarkError):
    """Result folders that cannot be merged into one table (bad input, exit 2)."""


@dataclass(frozen=True)
class Entry:
    """One method on one split: its rank, figures (seeds pooled), seeds, folder and comparison with the first."""

    rank: int
    row: Row
    seeds: int
    folder: str
    against_first: Comparison | None
    left_out: int = 0  # episodes of this method on scenarios not every method ran (not in its row)

    def to_dict(self) -> dict[str, Any]:
        data = {"rank": self.rank, "seeds": self.seeds, "folder": self.folder, "left_out": self.left_out}
        data.update(asdict(self.row))
        data["against_first"] = asdict(self.against_first) if self.against_first else None
        return {k: None if isinstance(v, float) and math.isnan(v) else v for k, v in data.items()}


def merge_folders(folders: Sequence[str | Path]) -> list[dict[str, Any]]:
    """Every record of ``folders``' ``results.json``, with ``folder``; :class:`LeaderboardError` if not comparable."""
    if not folders:
        raise LeaderboardError("give at least one results folder")
    merged: list[dict[str, Any]] = []
    owner: dict[tuple[str, str], str] = {}  # (method, split) -> folder
    for folder in map(Path, folders):
        path = results_file(folder) if folder.is_dir() else folder
        try:
            records = read_results(path)
        except FileNotFoundError:
            raise LeaderboardError(f"{folder}: no {RESULTS} (a fetchcarry benchmark --out folder)") from None
        for record in records:  # the reader's own dicts: marked in place, not copied
            record["folder"] = str(folder)
        keys = {(method_of(r)[0], r["split"]) for r in records}
        for method, split in keys:
            first = owner.get((method, split))
            if first is not None and method not in SHARED:
                raise LeaderboardError(
                    f"{method} on {split} is in both {first} and {folder}: give its runs other names"
                )
        fresh = {key for key in keys if key not in owner}
        merged += [r for r in records if (method_of(r)[0], r["split"]) in fresh]
        owner.update({key: str(folder) for key in fresh})
    _check_comparable(merged)
    return merged


def _check_comparable(records: list[dict[str, Any]]) -> None:
    """One version per split, one reference per split."""
    versions: dict[str, dict[str, str]] = {}  # base name (iid) -> version (iid-v1) -> the first folder with it
    for r in records:
        split = SPLITS.get(r["split"])
        base, version = (split.base_name, split.version) if split else (r["split"], r["split"])
        versions.setdefault(base, {}).setdefault(version, r["folder"])
    for base, seen in versions.items():
        if len(seen) > 1:
            listed = ", ".join(f"{name} ({folder})" for name, folder in seen.items())
            raise LeaderboardError(f"results of different versions of {base}: {listed}; benchmark them on one version")
    refs: dict[str, dict[Any, str]] = {}
    for r in records:
        refs.setdefault(r["split"], {}).setdefault(r.get("references"), r["folder"])
    for split, seen in refs.items():
        if len(seen) > 1:
            listed = ", ".join(f"{(d or 'its own expert run')[:12]} ({folder})" for d, folder in seen.items())
            raise LeaderboardError(f"results on {split} against different references: {listed}")


def leaderboard(records: Sequence[dict[str, Any]]) -> dict[str, list[Entry]]:
    """Per split, the methods ranked by success then SPL on the scenarios they all ran, each compared with the first.

    :class:`LeaderboardError` when the methods of a split share no scenario. The records
    are pooled and grouped by split and method once: the time is linear in the records
    (and the rows' bootstraps), however many splits and methods they name.
    """
    table = grouped(pooled(records))
    out: dict[str, list[Entry]] = {}
    for split, methods in table.items():
        shared, left_out = shared_scenarios(split, methods)
        methods = {m: [r for r in group if scenario_key(r) in shared] for m, group in methods.items()}
        ranked = sorted(
            summarise([r for group in methods.values() for r in group]), key=lambda row: (-row.success, -_or0(row.spl))
        )
        entries = []
        for rank, row in enumerate(ranked, 1):
            against = None if rank == 1 else compare_methods(methods, row.policy, ranked[0].policy, split)
            group = methods[row.policy]
            seeds = len({r["training_seed"] for r in group} - {None}) or 1
            folder = group[0].get("folder", "")
            entries.append(Entry(rank, row, seeds, folder, against, left_out[row.policy]))
        out[split] = entries
    return out


def scenario_key(record: dict[str, Any]) -> tuple[int, Any]:
    return (record["seed"], record.get("digest"))


def shared_scenarios(split: str, methods: dict[str, list[dict[str, Any]]]) -> tuple[set, dict[str, int]]:
    """The scenarios every method of ``split`` ran, and per method its episodes on the others."""
    ran = {method: {scenario_key(r) for r in group} for method, group in methods.items()}
    shared = set.intersection(*ran.values())
    if not shared:
        counts = ", ".join(f"{method} {len(scenarios)}" for method, scenarios in ran.items())
        raise LeaderboardError(
            f"on {split} no scenario was run by every method (scenarios per method: {counts}); "
            "benchmark them on the same split part and episodes"
        )
    return shared, {method: sum(scenario_key(r) not in shared for r in group) for method, group in methods.items()}


def _or0(value: float) -> float:
    return 0.0 if math.isnan(value) else value


def _shared_note(entries: list[Entry]) -> list[str]:
    """A line saying which episodes were left out because not every method ran their scenarios (none if none)."""
    left = [f"{e.row.policy} {e.left_out}" for e in entries if e.left_out]
    if not left:
        return []
    return [
        f"Ranked on the {entries[0].row.scenarios} scenarios every method ran; episodes on other scenarios left "
        f"out: {', '.join(left)}.",
        "",
    ]


def leaderboard_markdown(board: dict[str, list[Entry]]) -> str:
    """The ranked tables in Markdown, with the legend of the benchmark's columns."""
    lines = ["# Leaderboard", ""]
    for split, entries in board.items():
        first = entries[0].row.policy  # the column's header names it
        lines += [f"## {split}", "", *_shared_note(entries)]
        lines += [
            f"| rank | method | seeds | n | success [95 % CI] | cost ratio [95 % CI] | SPL | score | "
            f"success - {first} [95 % CI] | seeds up/down (p) | folder |",
            "| --- " * 11 + "|",
        ]
        for e in entries:
            row, c = e.row, e.against_first
            ratio = (
                "-"
                if math.isnan(row.cost_ratio)
                else f"{row.cost_ratio:.3f}"
                + ("" if math.isnan(row.cost_ratio_low) else f" [{row.cost_ratio_low:.3f}, {row.cost_ratio_high:.3f}]")
            )
            diff = (
                "-"
                if c is None
                else (f"{100 * c.success_diff:+.1f} pts [{100 * c.success_low:+.1f}, {100 * c.success_high:+.1f}]")
            )
            signs = "-" if c is None else f"{c.seed_wins}/{c.seed_losses} ({c.sign_p:.2g})"
            score = "-" if math.isnan(row.score) else f"{row.score:.1f}"
            spl = "-" if math.isnan(row.spl) else f"{row.spl:.3f}"
            lines.append(
                f"| {e.rank} | {row.policy} | {e.seeds} | {row.episodes} | {row.success:.1%} [{row.success_low:.1%}, "
                f"{row.success_high:.1%}] | {ratio} | {spl} | {score} | {diff} | {signs} | {e.folder} |"
            )
        lines.append("")
    lines += [
        *legend([e.row for entries in board.values() for e in entries]),
        "- success - FIRST: the paired bootstrap over the scenarios both ran of the per-scenario success "
        "difference with the method ranked first (seeds pooled); seeds up/down: training seeds whose success rate "
        "is above / below the first's, with the two-sided sign-test p-value.",
        "",
    ]
    return "\n".join(lines)
