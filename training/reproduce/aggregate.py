"""The published table from a reproduction's benchmark outputs: ``summary.md``, ``results.json`` and plots.

Every learned baseline was trained once per training seed, and each run was evaluated
on the same scenarios. Per split, ``summary.md`` gives each baseline's figures as the
mean over the training seeds with their range (min-max), and its success pooled over
the seeds (every episode of every seed) with a 95 % Wilson interval; the references
(expert, random, random-phases, greedy) have one evaluation each. ``results.json``
holds every episode record of every split, with two keys added to the benchmark's:
``baseline`` (the label without the seed) and ``training_seed`` (``null`` for the
references and for ``dagger-aimed-ensemble``, which is made of every seed's runs).
Plots: ``splits.png`` (success and cost ratio per split, pooled over the
seeds, with 95 % intervals), ``objects.png`` (the same against the object count on the
graded worlds, ``objects``), ``ppo_curves.png`` (MaskablePPO's training success and
return against env steps and wall-clock seconds, one line per run) and
``demonstrations.png`` (BC's success on ``iid`` against its expert episodes), drawn by
:mod:`training.pictures.benchmark`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from training.evaluation.metrics import Row, by_objects, summarise
from training.evaluation.report import source_table
from training.evaluation.results import RESULTS, RESULTS_GZIP, read_results, write_results
from training.learners.runs import read_saved
from training.pictures.benchmark import plot_against_objects, plot_demonstrations, plot_ppo_curves, plot_splits
from training.reproduce.budgets import Budget
from training.reproduce.publish import commit_line
from training.reproduce.table import CURVE_SPLIT, OBJECTS_SPLIT, Baseline, on_curve_only

SUMMARY, SPLITS_PLOT, OBJECTS_PLOT = "summary.md", "splits.png", "objects.png"
CURVES_PLOT, DEMONSTRATIONS_PLOT = "ppo_curves.png", "demonstrations.png"
PPO_BASELINES = ("ppo-scratch", "ppo-bc")


def collect(out: Path, baselines: Sequence[Baseline], splits: Sequence[str]) -> list[dict[str, Any]]:
    """Every benchmark record of ``splits`` in the reproduction ``out``, with ``baseline`` and ``training_seed``."""
    owner = {name: (b.label, seed if b.per_seed else None) for b in baselines for seed, name in enumerate(b.runs)}
    records = []
    for split in splits:
        for record in read_results(out / "benchmark" / split / RESULTS):
            label, seed = owner.get(record["policy"], (record["policy"], None))
            records.append({**record, "baseline": label, "training_seed": seed})
    return records


def expert_labels(run: Path) -> int | None:
    """The expert labels a bc or dagger run was trained on (from its config.json), None for ppo."""
    data = read_saved(run).get("data") or {}
    for key in ("labelled", "expert_labels"):
        if isinstance(data.get(key), int):
            return data[key]
    return None


def write_published(
    out: Path, baselines: Sequence[Baseline], budget: Budget, seeds: int, timings: dict, commits: Sequence[str] = ()
) -> Path:
    """Write ``summary.md``, ``results.json`` and the plots of the reproduction in ``out``; return summary.md's path.

    ``commits`` are the commits of the code that made the folder (:func:`training.reproduce.publish.record_commit`):
    the summary names them.
    """
    records = collect(out, baselines, budget.splits)
    write_results(out / RESULTS, records)
    per_run = {(row.policy, row.split): row for row in summarise(records)}
    pooled = {(row.policy, row.split): row for row in summarise([{**r, "policy": r["baseline"]} for r in records])}
    labels = {name: expert_labels(out / "runs" / name) for b in baselines for name in b.runs}
    main = [b for b in baselines if not on_curve_only(b.label)]
    learned = {b.label for b in baselines}
    references = list(dict.fromkeys(r["baseline"] for r in records if r["baseline"] not in learned))
    lines = [
        "# The published table",
        "",
        commit_line(commits) if commits else "Commit not recorded.",
        "",
        f"Budget `{budget.name}`, {seeds} training seed(s), {budget.episodes} episodes per split (the test parts; "
        "fewer where a split's test part has fewer references: the count is in each section's title); "
        "learners trained on the `training` family (basic, push, corridor, multi-2)"
        + (f" at the observation capacity {budget.capacity}" if budget.capacity else "")
        + ". Learned baselines: the mean "
        "over training seeds with the range (min-max) in brackets; success also pooled over the seeds' episodes "
        "with a 95 % bootstrap interval over scenarios (each scenario's seeds kept together: they are not "
        "independent trials). Cost ratio: travel cost over the split's fixed reference on the same scenario "
        "(episodes both solved). Score: its zero is random-phases. Paired comparisons: `fetchcarry compare A B "
        "--results DIR/benchmark/SPLIT`.",
        "",
    ]
    for split in dict.fromkeys(r["split"] for r in records):
        scenarios = len({r["seed"] for r in records if r["split"] == split})
        lines += [f"## {split} ({scenarios} scenarios)", ""]
        lines += [*_table(split, references, main, per_run, pooled, labels), ""]
        caption = f"Per scenario source ({split}): success pooled over the seeds [95 % CI], cost ratio in brackets."
        by_baseline = [{**r, "policy": r["baseline"]} for r in records]
        lines += source_table(by_baseline, split, caption, references + [b.label for b in main], first="baseline")
    curve = [b for b in baselines if b.demonstrations is not None and b.label.startswith("bc-mlp")]
    curve_split = next((s for s in dict.fromkeys(r["split"] for r in records) if s.startswith(CURVE_SPLIT)), None)
    if curve_split is not None:
        lines += [f"## BC (flat MLP) against expert demonstrations, {curve_split}", ""]
        lines += _curve_table(curve_split, curve, [b for b in baselines if b.label == "dagger"], per_run, pooled,
                              labels, budget)  # fmt: skip
        lines.append("")
    lines += ["## Time", "", "| stage | wall-clock s | CPU s |", "| --- | --- | --- |"]
    for name, entry in timings.get("stages", {}).items():
        if isinstance(entry, dict):
            lines.append(f"| {name} | {entry['wall']:.0f} | {entry['cpu']:.0f} |")
    graded = [{**r, "policy": r["baseline"]} for r in records if r["split"].startswith(f"{OBJECTS_SPLIT}-")]
    plots = [SPLITS_PLOT, *([OBJECTS_PLOT] if graded else []), CURVES_PLOT, DEMONSTRATIONS_PLOT]
    lines += ["", f"Plots: {', '.join(plots)}; every record: {RESULTS} ({RESULTS_GZIP} in a published copy).", ""]
    (out / SUMMARY).write_text("\n".join(lines))
    shown = references + [b.label for b in main]
    plot_splits([row for key, row in pooled.items() if key[0] in shown], out / SPLITS_PLOT)
    if graded:  # success and cost ratio against the object count, k = 1..8
        rows = by_objects([r for r in graded if r["policy"] in shown])
        plot_against_objects(rows, out / OBJECTS_PLOT, title=graded[0]["split"])
    plot_ppo_curves(ppo_metrics(out / "runs", [b for b in baselines if b.label in PPO_BASELINES]), out / CURVES_PLOT)
    points = [{**r, "policy": "bc-mlp", "demonstrations": _demonstrations(r, curve)} for r in records
              if curve_split is not None and r["split"] == curve_split and _demonstrations(r, curve)]  # fmt: skip
    plot_demonstrations(points, out / DEMONSTRATIONS_PLOT)
    return out / SUMMARY


def _demonstrations(record: dict[str, Any], curve: Sequence[Baseline]) -> int | None:
    return next((b.demonstrations for b in curve if b.label == record["baseline"]), None)


HEADER = (
    "| baseline | seeds | success, pooled [95 % CI] | success per seed | delivered / ep | cost ratio | SPL (cost) "
    "| phases (expert) | pushes (expert) | invalid / ep | contacts / ep | ms / decision (planner) | score "
    "| expert labels |"
)


def _table(split: str, references: list[str], main: Sequence[Baseline], per_run: dict, pooled: dict,
           labels: dict) -> list[str]:  # fmt: skip
    lines = [HEADER, "|" + " --- |" * HEADER.count(" | ") + " --- |"]
    for name in references:
        row = per_run.get((name, split))
        if row is not None:
            lines.append(
                _line(name, [row], pooled[(name, split)], [None]).replace(f"| {name} | 1 |", f"| {name} | - |")
            )
    for baseline in main:
        rows = [per_run[(name, split)] for name in baseline.runs if (name, split) in per_run]
        if rows:
            counts = [labels[n] for n in baseline.runs]
            lines.append(_line(baseline.label, rows, pooled[(baseline.label, split)], counts))
    return lines


def _line(label: str, rows: list[Row], pooled: Row, labels: list[int | None]) -> str:
    def cell(key: str, fmt: str) -> str:
        return _spread([getattr(r, key) for r in rows], fmt)

    cells = [
        label,
        str(len(rows)),
        f"{pooled.success:.1%} [{pooled.success_low:.1%}, {pooled.success_high:.1%}]",
        cell("success", "{:.1%}"),
        cell("delivered", "{:.2f}"),
        cell("cost_ratio", "{:.3f}"),
        cell("spl", "{:.3f}"),
        f"{cell('phases', '{:.1f}')} ({rows[0].expert_phases:.1f})",
        f"{cell('pushes', '{:.2f}')} ({rows[0].expert_pushes:.2f})",
        cell("invalid_actions", "{:.2f}"),
        cell("contacts", "{:.2f}"),
        f"{cell('decision_ms', '{:.2f}')} ({rows[0].planner_ms:.1f})",
        cell("score", "{:.1f}"),
        _spread([float(n) for n in labels if n is not None], "{:.0f}"),
    ]
    return "| " + " | ".join(cells) + " |"


def _spread(values: list[float], fmt: str) -> str:
    """``mean (min-max)`` of the finite ``values``, ``mean`` for one, ``-`` for none."""
    finite = [v for v in values if not math.isnan(v)]
    if not finite:
        return "-"
    mean = fmt.format(float(np.mean(finite)))
    if len(finite) == 1:
        return mean
    return f"{mean} ({fmt.format(min(finite))}-{fmt.format(max(finite))})"


def _curve_table(split: str, curve: Sequence[Baseline], dagger: Sequence[Baseline], per_run: dict, pooled: dict,
                 labels: dict, budget: Budget) -> list[str]:  # fmt: skip
    lines = [
        "| baseline | expert episodes | expert labels | success, pooled [95 % CI] | success per seed | cost ratio |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    dagger_episodes = budget.dagger_demonstrations + budget.dagger_iterations * budget.dagger_episodes
    entries = sorted(((b.demonstrations, b) for b in curve), key=lambda e: e[0])
    entries += [(dagger_episodes, b) for b in dagger]
    for episodes, baseline in entries:
        rows = [per_run[(n, split)] for n in baseline.runs if (n, split) in per_run]
        if not rows:
            continue
        row = pooled[(baseline.label, split)]
        counts = _spread([float(labels[n]) for n in baseline.runs if labels[n]], "{:.0f}")
        lines.append(
            f"| {baseline.label} | {episodes} | {counts} "
            f"| {row.success:.1%} [{row.success_low:.1%}, {row.success_high:.1%}] "
            f"| {_spread([r.success for r in rows], '{:.1%}')} | {_spread([r.cost_ratio for r in rows], '{:.3f}')} |"
        )
    return lines


def ppo_metrics(runs: Path, ppo: Sequence[Baseline]) -> list[tuple[str, list[list[dict[str, float]]]]]:
    """Per PPO baseline, its label and each run's ``metrics.csv`` rows (an empty list for a run without one)."""
    from training.learners.runs import read_metrics  # training.learners.runs imports torch

    return [
        (b.label, [read_metrics(runs / name) if (runs / name / "metrics.csv").is_file() else [] for name in b.runs])
        for b in ppo
    ]
