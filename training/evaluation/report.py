"""What the benchmark writes for people: the ``summary.md`` table and PNG plots.

:func:`summary_markdown` makes one table row per policy and split; :func:`plot_splits`
draws success and cost ratio per split with their 95 % intervals;
:func:`plot_learning_curve` draws a run folder's ``metrics.csv`` (any numeric columns
against its first); :func:`plot_demonstrations` draws success against the number of
demonstrations from records that carry a ``demonstrations`` count.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from training.evaluation.metrics import Z_95, Row, summarise, wilson

COLUMNS = (
    ("policy", "policy", "{}"),
    ("split", "split", "{}"),
    ("episodes", "n", "{}"),
    ("success", "success [95 % CI]", None),
    ("delivered", "delivered / ep", "{:.2f}"),
    ("cost_ratio", "cost ratio", "{:.3f}"),
    ("spl", "SPL (cost)", "{:.3f}"),
    ("phases", "phases (expert)", None),
    ("pushes", "pushes (expert)", None),
    ("invalid_actions", "invalid / ep", "{:.2f}"),
    ("contacts", "contacts / ep", "{:.2f}"),
    ("decision_ms", "ms / decision (planner)", None),
    ("mask_ms", "mask ms", "{:.2f}"),
    ("score", "score", "{:.1f}"),
)


def _cell(row: Row, key: str, fmt: str | None) -> str:
    if key == "success":
        return f"{row.success:.1%} [{row.success_low:.1%}, {row.success_high:.1%}]"
    if key == "phases":
        return f"{row.phases:.1f} ({row.expert_phases:.1f})"
    if key == "pushes":
        return f"{row.pushes:.2f} ({row.expert_pushes:.2f})"
    if key == "decision_ms":
        return f"{row.decision_ms:.2f} ({row.planner_ms:.1f})"
    value = getattr(row, key)
    if isinstance(value, float) and math.isnan(value):
        return "-"
    return fmt.format(value)


def summary_markdown(rows: Sequence[Row], title: str = "Benchmark") -> str:
    """The table of ``rows`` in Markdown, with a legend of what each column means."""
    lines = [
        f"# {title}",
        "",
        "| " + " | ".join(header for _, header, _ in COLUMNS) + " |",
        "|" + "|".join(" --- " for _ in COLUMNS) + "|",
    ]
    lines += ["| " + " | ".join(_cell(row, key, fmt) for key, _, fmt in COLUMNS) + " |" for row in rows]
    lines += [
        "",
        "- success: episodes that delivered every object, with a 95 % Wilson interval.",
        "- cost ratio: the paper's travel cost over the MILP expert's on the same scenario, "
        "mean over episodes both solved. SPL (cost): success x expert cost / max(cost, expert cost), "
        "mean over episodes the expert solved.",
        "- phases and pushes per episode, the expert's on the same scenarios in brackets; "
        "contacts: stops at a contact (the env's `collisions`).",
        "- ms / decision: wall time of the policy's decision, the expert's (the planner's) in brackets; "
        "mask ms: the env's action masks handed to the policy, per decision. Timings depend on the machine's load.",
        "- score: 100 x (R - R_random) / (R_expert - R_random), R the mean episode return "
        "(the paper's reward: +10 per delivery, minus travel cost and penalties).",
        "",
    ]
    return "\n".join(lines)


def source_table(
    records: Sequence[dict[str, Any]],
    split: str,
    caption: str,
    policies: Sequence[str] | None = None,
    first: str = "policy",
) -> list[str]:
    """Per scenario source of ``split`` (a family, or a push pattern): each policy's success and cost ratio.

    Markdown lines: ``caption``, then one row per policy (``policies``, or every one in the
    records' order; ``first`` heads the column) and one column per source, each cell the
    success with its 95 % Wilson interval and the cost ratio in brackets; no lines when
    ``split`` has one source.
    """
    chosen = [{**r, "split": r.get("source", split)} for r in records if r["split"] == split]
    sources = list(dict.fromkeys(r["split"] for r in chosen))
    if len(sources) < 2:
        return []
    rows = {(row.policy, row.split): row for row in summarise(chosen)}
    lines = [caption, "", f"| {first} | " + " | ".join(sources) + " |", "| --- |" + " --- |" * len(sources)]
    for name in policies if policies is not None else dict.fromkeys(r["policy"] for r in chosen):
        cells = [rows.get((name, source)) for source in sources]
        lines.append(f"| {name} | " + " | ".join(_success_and_ratio(c) if c else "-" for c in cells) + " |")
    return [*lines, ""]


def _success_and_ratio(row: Row) -> str:
    ratio = "-" if math.isnan(row.cost_ratio) else f"{row.cost_ratio:.2f}"
    return f"{row.success:.0%} [{row.success_low:.0%}, {row.success_high:.0%}] ({ratio})"


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_splits(rows: Sequence[Row], path: str | Path) -> Path:
    """Success and cost ratio per split and policy, with 95 % intervals, as one PNG."""
    plt = _pyplot()
    splits = list(dict.fromkeys(r.split for r in rows))
    policies = list(dict.fromkeys(r.policy for r in rows))
    by_key = {(r.policy, r.split): r for r in rows}
    width = 0.8 / max(1, len(policies))
    figure, (left, right) = plt.subplots(1, 2, figsize=(max(8.0, 2.5 * len(splits) + 4), 4))
    for k, policy in enumerate(policies):
        xs, success, s_err, ratio, r_err, r_xs = [], [], [[], []], [], [[], []], []
        for j, split in enumerate(splits):
            row = by_key.get((policy, split))
            if row is None:
                continue
            x = j + (k - (len(policies) - 1) / 2) * width
            xs.append(x)
            success.append(row.success)
            s_err[0].append(row.success - row.success_low)
            s_err[1].append(row.success_high - row.success)
            if not math.isnan(row.cost_ratio):
                r_xs.append(x)
                ratio.append(row.cost_ratio)
                low = row.cost_ratio_low if not math.isnan(row.cost_ratio_low) else row.cost_ratio
                high = row.cost_ratio_high if not math.isnan(row.cost_ratio_high) else row.cost_ratio
                r_err[0].append(row.cost_ratio - low)
                r_err[1].append(high - row.cost_ratio)
        left.bar(xs, success, width, yerr=s_err, capsize=3, label=policy)
        right.bar(r_xs, ratio, width, yerr=r_err, capsize=3, label=policy)
    for axis, label in ((left, "success rate (95 % Wilson)"), (right, "cost ratio to the expert (95 % CI)")):
        axis.set_xticks(range(len(splits)), splits)
        axis.set_ylabel(label)
    left.set_ylim(0, 1.05)
    right.axhline(1.0, color="grey", linewidth=0.8)
    handles, labels = left.get_legend_handles_labels()
    figure.legend(handles, labels, loc="upper center", ncol=min(len(policies), 6), fontsize="small", frameon=False)
    figure.tight_layout(rect=(0, 0, 1, 0.92))
    figure.savefig(path, dpi=100)
    plt.close(figure)
    return Path(path)


def plot_learning_curve(
    run_dir: str | Path, path: str | Path, columns: Sequence[str] | None = None, x: str | None = None
) -> Path:
    """A run folder's ``metrics.csv``: each numeric column (or ``columns``) against ``x`` (default: the first column).

    ``x="seconds"`` (or whatever column holds wall-clock time) draws the curves against time.
    """
    with (Path(run_dir) / "metrics.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    if not rows:
        raise ValueError(f"{Path(run_dir) / 'metrics.csv'} has no rows")
    x_key = x if x is not None else next(iter(rows[0]))
    if x_key not in rows[0]:
        raise ValueError(f"{Path(run_dir) / 'metrics.csv'} has no column {x_key!r}")
    keys = list(columns) if columns is not None else [k for k in rows[0] if k != x_key and _numeric(rows, k)]
    plt = _pyplot()
    figure, axes = plt.subplots(1, len(keys), figsize=(4 * len(keys), 3.2), squeeze=False)
    xs = [float(r[x_key]) for r in rows]
    for axis, key in zip(axes[0], keys, strict=True):
        axis.plot(xs, [float(r[key]) for r in rows])
        axis.set_xlabel(x_key)
        axis.set_ylabel(key)
    figure.suptitle(Path(run_dir).name)
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    plt.close(figure)
    return Path(path)


def _numeric(rows: list[dict[str, str]], key: str) -> bool:
    try:
        [float(r[key]) for r in rows]
    except (TypeError, ValueError):
        return False
    return True


def plot_demonstrations(records: Sequence[dict[str, Any]], path: str | Path) -> Path:
    """Success against the number of demonstrations (log scale), one line per policy, 95 % Wilson bands.

    Each record needs ``policy``, ``demonstrations`` (expert episodes the policy was trained on) and ``success``.
    """
    groups: dict[str, dict[int, list[bool]]] = {}
    for record in records:
        groups.setdefault(record["policy"], {}).setdefault(int(record["demonstrations"]), []).append(
            bool(record["success"])
        )
    plt = _pyplot()
    figure, axis = plt.subplots(figsize=(5, 3.5))
    for policy, points in groups.items():
        counts = sorted(points)
        rates = [sum(points[n]) / len(points[n]) for n in counts]
        bands = [wilson(sum(points[n]), len(points[n]), Z_95) for n in counts]
        axis.plot(counts, rates, marker="o", label=policy)
        axis.fill_between(counts, [b[0] for b in bands], [b[1] for b in bands], alpha=0.2)
    axis.set_xscale("log")
    axis.set_xlabel("expert demonstrations (episodes)")
    axis.set_ylabel("success rate")
    axis.set_ylim(0, 1.05)
    axis.legend(fontsize="small")
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    plt.close(figure)
    return Path(path)
