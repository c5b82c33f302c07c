"""The text the benchmark writes for people: the ``summary.md`` tables.

:func:`summary_markdown` makes one table row per policy and split, with a legend of the
columns; :func:`source_table` gives each policy's success and cost ratio per scenario
source of a split. The plots are :mod:`training.pictures.benchmark`'s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from training.evaluation.metrics import Row, summarise

__all__ = ["COLUMNS", "source_table", "summary_markdown"]

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
