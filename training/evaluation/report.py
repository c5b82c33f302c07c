"""The text the benchmark writes for people: the ``summary.md`` tables.

:func:`summary_markdown` makes one table row per policy and split, with a legend of the
columns; :func:`source_table` gives each policy's success and cost ratio per scenario
source of a split. The plots are :mod:`training.pictures.benchmark`'s.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Any

from fetchcarry_env.registration import MAX_EPISODE_STEPS, do_nothing_return
from training.evaluation.metrics import Row, grouped

__all__ = ["COLUMNS", "source_table", "summary_markdown"]

COLUMNS = (
    ("policy", "policy", "{}"),
    ("split", "split", "{}"),
    ("episodes", "n", "{}"),
    ("success", "success [95 % CI]", None),
    ("delivered", "delivered / ep", "{:.2f}"),
    ("cost_ratio", "cost ratio [95 % CI]", None),
    ("spl", "SPL (cost)", "{:.3f}"),
    ("phases", "phases (expert)", None),
    ("pushes", "pushes (expert)", None),
    ("invalid_actions", "invalid / ep", "{:.2f}"),
    ("contacts", "contacts / ep", "{:.2f}"),
    ("decision_ms", "policy ms (planner)", None),
    ("mask_ms", "mask ms", "{:.2f}"),
    ("step_ms", "step ms", "{:.1f}"),
    ("score", "score", "{:.1f}"),
)


def _cell(row: Row, key: str, fmt: str | None) -> str:
    if key == "success":
        return f"{row.success:.1%} [{row.success_low:.1%}, {row.success_high:.1%}]"
    if key == "cost_ratio":
        if math.isnan(row.cost_ratio):
            return "-"
        interval = "" if math.isnan(row.cost_ratio_low) else f" [{row.cost_ratio_low:.3f}, {row.cost_ratio_high:.3f}]"
        return f"{row.cost_ratio:.3f}{interval}"
    if key == "episodes" and row.scenarios and row.scenarios != row.episodes:
        return f"{row.episodes} ({row.scenarios} scenarios)"
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
    lines += ["", *legend(rows), ""]
    return "\n".join(lines)


def legend(rows: Sequence[Row]) -> list[str]:
    """The lines under a table of ``rows`` that say what each column means and where its reference comes from."""
    kinds = sorted({row.reference for row in rows})
    disagreements = [
        f"{row.split}: {row.disagreements} of {row.episodes}"
        for row in rows
        if row.policy == "expert" and row.reference != "expert run"
    ]
    reference = (
        "the split's fixed reference (the expert once, with a generous planning limit; training/evaluation/references)"
        if kinds == ["fixed"]
        else f"reference: {', '.join(kinds)} "
        "(fixed: the split's reference file; expert run: this run's expert, timing-dependent)"
    )
    lines = [
        "- success: episodes that delivered every object, with a 95 % interval (Wilson with one episode per "
        "scenario; with training seeds pooled, a two-stage bootstrap: training seeds, then scenarios, keeping each "
        "scenario's seeds together; never narrower than Wilson's interval of the same counts). n: episodes (and "
        "distinct scenarios when seeds are pooled).",
        f"- cost ratio: the episode's task cost (travel, 10 per object and phase before its delivery, penalties: "
        f"minus the return) over {reference} on the same scenario, mean over episodes both "
        "solved, with a 95 % bootstrap interval over scenarios. SPL (cost): success x reference cost / "
        "max(cost, reference cost), mean over episodes the reference solved.",
        "- phases and pushes per episode, the reference's on the same scenarios in brackets; "
        "contacts: stops at a contact (the env's `collisions`).",
        "- policy ms: wall time of the policy's decision, the expert's (the planner's) in brackets; "
        "mask ms: the env's action masks handed to the policy; step ms: the whole step (policy, mask and the "
        "env), per decision. Timings depend on the machine's load.",
        "- score: 100 x sum(R - F) / sum(R_reference - F) over the scenarios whose reference succeeded, R the "
        "episode's return (the env's reward: minus the task cost), F the scenario's do-nothing return (every "
        f"object waiting all {MAX_EPISODE_STEPS} phases: {do_nothing_return(1):.0f} per object): 0 for doing "
        "nothing, 100 for the reference; a failed "
        "episode counts at most F and a successful one at least F, so no failure scores above a success.",
    ]
    if disagreements:
        lines.append(
            f"- the expert row against the fixed reference: disagreements (success, or cost by 0.001) "
            f"{'; '.join(disagreements)}."
        )
    return lines


def family_of(record: dict[str, Any]) -> str:
    """The scenario family of a record: its ``family`` field, else its file name without the trailing number.

    ``objects-3-0007.json`` is family ``objects-3``, ``basic-565565.json`` ``basic``, and a
    name without a trailing number (``push_basic.json``) its own family.
    """
    if isinstance(record.get("family"), str):
        return record["family"]
    stem = record.get("source", "").rsplit(".json", 1)[0]
    match = re.match(r"^(.*?)[-_]?\d+$", stem)
    return match[1] if match and match[1] else stem


def source_table(
    records: Sequence[dict[str, Any]],
    split: str,
    caption: str,
    policies: Sequence[str] | None = None,
    first: str = "policy",
) -> list[str]:
    """Per scenario source of ``split`` (a family, or a push pattern): each policy's success and cost ratio.

    For a folder of scenario files (``scenarios:FOLDER``) a source is the file's family
    (:func:`family_of`), so that a folder of many files gives a column per family, not per file.

    Markdown lines: ``caption``, then one row per policy (``policies``, or every one in the
    records' order; ``first`` heads the column) and one column per source, each cell the
    success with its 95 % interval (as the table's) and the cost ratio in brackets; no lines when
    ``split`` has one source.
    """
    files = split.startswith("scenarios:")
    chosen = [r for r in records if r["split"] == split]
    key = family_of if files else lambda r: r.get("source", split)
    sources = list(dict.fromkeys(key(r) for r in chosen))
    if len(sources) < 2:
        return []
    rows = {(row.policy, row.split): row for row in grouped(chosen, key)}
    lines = [caption, "", f"| {first} | " + " | ".join(sources) + " |", "| --- |" + " --- |" * len(sources)]
    for name in policies if policies is not None else dict.fromkeys(r["policy"] for r in chosen):
        cells = [rows.get((name, source)) for source in sources]
        lines.append(f"| {name} | " + " | ".join(_success_and_ratio(c) if c else "-" for c in cells) + " |")
    return [*lines, ""]


def _success_and_ratio(row: Row) -> str:
    ratio = "-" if math.isnan(row.cost_ratio) else f"{row.cost_ratio:.2f}"
    return f"{row.success:.0%} [{row.success_low:.0%}, {row.success_high:.0%}] ({ratio})"
