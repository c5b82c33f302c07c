"""The benchmark's and the published table's plots, as PNG files.

:func:`plot_splits` draws success and cost ratio per split (or per object count) with
their 95 % intervals, a distinct colour for every policy (:func:`policy_colours`) and n in
the caption (per group, in the order of the x axis, where it differs between groups);
:func:`plot_against_objects` draws success and cost ratio against the object count, one line per policy.
A bar or point without an interval (one scenario) is marked "no CI", never drawn with an
error bar of zero width. :func:`splits_figure` and :func:`objects_figure` return their figures.
:func:`plot_learning_curve` draws a run folder's ``metrics.csv`` (any numeric columns
against its first); :func:`plot_demonstrations` draws success against the number of
demonstrations from records that carry a ``demonstrations`` count;
:func:`plot_ppo_curves` draws PPO runs' training success and return against env steps
and wall-clock seconds. Headless (matplotlib's Agg canvas).

matplotlib is imported by :func:`pyplot` when a plot is drawn, not with this module:
the benchmark's runner imports this module, and the command line, which imports the
runner, starts without matplotlib.
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fetchcarry_env.errors import InputError
from training.stats import Z_95, wilson

if TYPE_CHECKING:
    from training.evaluation.metrics import Row

DPI = 100  # dots per inch of every plot
MARKER_SIZE = 4  # points: every curve marks its points, so a run with one row shows as a dot, not as nothing


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the headless Agg backend (imported on the first plot: it takes about 0.3 s)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


REFERENCE_COLOURS = {"expert": "#000000", "random-phases": "#7f7f7f", "random": "#bdbdbd", "greedy": "#8c564b"}
ZERO_MARK = 0.03  # success axis units: a bar of zero success is drawn this high, hatched and labelled "0", so it shows


def policy_colours(policies: Sequence[str]) -> dict[str, Any]:
    """A distinct colour for every policy: fixed ones for the references, then tab10, tab20b, tab20c, then hues."""
    plt = pyplot()
    palette = [c for name in ("tab10", "tab20b", "tab20c") for c in plt.get_cmap(name).colors]
    palette = [c for c in palette if plt.matplotlib.colors.to_hex(c) not in REFERENCE_COLOURS.values()]
    out: dict[str, Any] = {}
    others = [p for p in dict.fromkeys(policies) if p not in REFERENCE_COLOURS]
    for k, policy in enumerate(others):
        out[policy] = palette[k] if k < len(palette) else plt.get_cmap("hsv")((k - len(palette)) / max(1, len(others)))
    return {**{p: REFERENCE_COLOURS[p] for p in policies if p in REFERENCE_COLOURS}, **out}


def _caption(rows: Sequence[Row], bars: bool = True, missing_interval: bool = False) -> str:
    """``n = 300 episodes per bar (seeds pooled over 100 scenarios ...)``: what the bars (or points) are made of.

    Where the counts differ between groups (``row.split``), they are listed per group in the
    order of the x axis: ``n = 225 (1), 75 (2) episodes per bar``. ``missing_interval``: some
    bar or point has no interval (fewer than two scenarios), and the caption says so.
    """
    unit = "bar" if bars else "point"
    text = f"n = {_per_group(rows, lambda r: r.episodes)} episodes per {unit}"
    if any(r.scenarios and r.scenarios != r.episodes for r in rows):
        pooled = _per_group([r for r in rows if r.scenarios and r.scenarios != r.episodes], lambda r: r.scenarios)
        text += f" (seeds pooled over {pooled} scenarios; intervals resample scenarios)"
    kinds = sorted({r.reference for r in rows})
    reference = "the split's fixed reference" if kinds == ["fixed"] else f"the reference ({', '.join(kinds)})"
    stub = "; hatched stub marked 0: no success" if bars else ""
    no_interval = f"; {NO_INTERVAL}: fewer than two scenarios, no interval" if missing_interval else ""
    return text + f"{stub}{no_interval}; cost ratio to {reference}; score 0: doing nothing"


def _per_group(rows: Sequence[Row], count: Callable[[Row], int]) -> str:
    """The counts of ``rows``: ``"20, 60"`` if every group has the same ones, else per group in axis order.

    Per group: ``"225 (1), 75 (2)"``, a group of several counts as ``"20/60 (3)"``.
    """
    groups = {g: sorted({count(r) for r in rows if r.split == g}) for g in dict.fromkeys(r.split for r in rows)}
    if len({tuple(counts) for counts in groups.values()}) <= 1:
        return ", ".join(str(n) for n in sorted({count(r) for r in rows}))
    return ", ".join(f"{'/'.join(map(str, counts))} ({group})" for group, counts in groups.items())


NO_INTERVAL = "no CI"  # written over a bar or point that has no interval, instead of an error bar of zero width


def _interval(value: float, low: float, high: float) -> tuple[float, float] | None:
    """The error bar's lengths below and above ``value``, or None where there is no interval (NaN bounds)."""
    if math.isnan(value) or math.isnan(low) or math.isnan(high):
        return None
    return (value - low, high - value)


def _error_bars(axis: Any, points: list[tuple[float, float, tuple[float, float] | None]], **style: Any) -> None:
    """Error bars at ``(x, y, (below, above))``; where the interval is None, the words :data:`NO_INTERVAL` instead."""
    shown = [(x, y, e) for x, y, e in points if e is not None]
    if shown:
        errors = [[e[0] for _, _, e in shown], [e[1] for _, _, e in shown]]
        axis.errorbar([x for x, _, _ in shown], [y for _, y, _ in shown], yerr=errors, fmt="none", **style)
    for x, y, e in points:
        if e is None and not math.isnan(y):
            axis.annotate(NO_INTERVAL, (x, y), xytext=(0, 3), textcoords="offset points", ha="center", va="bottom",
                          fontsize="x-small", rotation=90)  # fmt: skip


def _bars(axes: Any, rows: Sequence[Row], groups: list[str], colours: dict[str, Any]) -> None:
    """Success and cost-ratio bars of ``rows`` per group (``row.split``) and policy, with their intervals."""
    left, right = axes
    policies = list(dict.fromkeys(r.policy for r in rows))
    by_key = {(r.policy, r.split): r for r in rows}
    width = 0.8 / max(1, len(policies))
    for k, policy in enumerate(policies):
        xs, success, s_err, r_xs, ratio, r_err, zero_xs = [], [], [], [], [], [], []
        for j, group in enumerate(groups):
            row = by_key.get((policy, group))
            if row is None:
                continue
            x = j + (k - (len(policies) - 1) / 2) * width
            xs.append(x)
            success.append(row.success)
            s_err.append(_interval(row.success, row.success_low, row.success_high))
            zero_xs += [x] if row.success == 0 else []
            if not math.isnan(row.cost_ratio):
                r_xs.append(x)
                ratio.append(row.cost_ratio)
                r_err.append(_interval(row.cost_ratio, row.cost_ratio_low, row.cost_ratio_high))
        colour = colours[policy]
        left.bar(xs, success, width, label=policy, color=colour, edgecolor="black", linewidth=0.3)
        _error_bars(left, list(zip(xs, success, s_err, strict=True)), ecolor="black", capsize=3)
        left.bar(
            zero_xs, [ZERO_MARK] * len(zero_xs), width, color="white", edgecolor=colour, hatch="////", linewidth=1.0
        )
        right.bar(r_xs, ratio, width, color=colour, edgecolor="black", linewidth=0.3)
        _error_bars(right, list(zip(r_xs, ratio, r_err, strict=True)), ecolor="black", capsize=3)
        for x in zero_xs:
            left.text(x, ZERO_MARK + 0.01, "0", ha="center", va="bottom", fontsize="x-small", color="black")


def _missing_interval(rows: Sequence[Row]) -> bool:
    """Whether a success or a cost ratio of ``rows`` is drawn without an interval."""
    return any(
        _interval(r.success, r.success_low, r.success_high) is None
        or (not math.isnan(r.cost_ratio) and _interval(r.cost_ratio, r.cost_ratio_low, r.cost_ratio_high) is None)
        for r in rows
    )


def plot_splits(rows: Sequence[Row], path: str | Path, groups_label: str | None = None) -> Path:
    """Success and cost ratio per split (or per group: ``row.split``) and policy, with 95 % intervals, as one PNG.

    Every policy has its own colour (:func:`policy_colours`), a bar of zero success shows
    as a hatched stub, a bar without an interval (one scenario) has "no CI" over it
    instead of an error bar, and the caption gives n (episodes per bar, and the scenarios
    when seeds are pooled; per group, in the order of the x axis, where it differs).
    ``groups_label`` names the x axis (the splits by default).
    """
    return _save(splits_figure(rows, groups_label), path)


def tick_label(name: str, width: int = 16) -> str:
    """A split's name on lines of about ``width`` characters at most, broken after a ``-`` or before a ``:``."""
    lines, line = [], ""
    for piece in re.findall(r"[^-:]+-?|:[^-:]+-?|-", name):
        if line and len(line) + len(piece) > width:
            lines.append(line)
            line = ""
        line += piece
    return "\n".join([*lines, line])


def splits_figure(rows: Sequence[Row], groups_label: str | None = None) -> Any:
    """The figure of :func:`plot_splits` (a pyplot figure: close it with ``pyplot().close``)."""
    plt = pyplot()
    groups = list(dict.fromkeys(r.split for r in rows))
    policies = list(dict.fromkeys(r.policy for r in rows))
    colours = policy_colours(policies)
    figure, axes = plt.subplots(1, 2, figsize=(max(8.0, 2.5 * len(groups) + 4), 4.4))
    _bars(axes, rows, groups, colours)
    left, right = axes
    for axis, label in ((left, "success rate (95 % CI)"), (right, "cost ratio to the reference (95 % CI)")):
        axis.set_xticks(range(len(groups)), [tick_label(g) for g in groups], fontsize="small")
        axis.set_ylabel(label)
        if groups_label:
            axis.set_xlabel(groups_label)
    left.set_ylim(0, 1.05)
    right.axhline(1.0, color="grey", linewidth=0.8)
    handles, labels = left.get_legend_handles_labels()
    figure.legend(handles, labels, loc="upper center", ncol=min(len(policies), 6), fontsize="small", frameon=False)
    figure.text(0.5, 0.01, _caption(rows, missing_interval=_missing_interval(rows)), ha="center", fontsize="x-small",
                wrap=True)  # fmt: skip
    rows_of_legend = math.ceil(len(policies) / 6)
    figure.tight_layout(rect=(0, 0.05, 1, 1 - 0.06 * rows_of_legend))
    return figure


def _save(figure: Any, path: str | Path) -> Path:
    """Write the pyplot ``figure`` to ``path`` at :data:`DPI` and close it."""
    figure.savefig(path, dpi=DPI)
    pyplot().close(figure)
    return Path(path)


def plot_against_objects(rows: Sequence[Row], path: str | Path, title: str = "") -> Path:
    """Success and cost ratio against the number of objects (``row.split`` is the count), one line per policy.

    The graded worlds' headline curve: a line per policy (its own colour) with its 95 %
    intervals as error bars, the policies side by side around each count so that the bars
    do not hide one another; n in the caption. A count where a policy solved nothing has
    no cost ratio: its cost line breaks there rather than join the counts around it. A
    point without an interval (one scenario) has "no CI" over it instead of an error bar.
    """
    return _save(objects_figure(rows, title), path)


def objects_figure(rows: Sequence[Row], title: str = "") -> Any:
    """The figure of :func:`plot_against_objects` (a pyplot figure: close it with ``pyplot().close``)."""
    plt = pyplot()
    policies = list(dict.fromkeys(r.policy for r in rows))
    rows = sorted(rows, key=lambda r: int(r.split))  # the caption's groups in the order of the axis
    colours = policy_colours(policies)
    figure, (left, right) = plt.subplots(1, 2, figsize=(12.0, 4.8))
    spread = 0.6  # objects: the width of one count's group of policies
    for n, policy in enumerate(policies):
        shift = spread * (n / max(1, len(policies) - 1) - 0.5)
        own = [r for r in rows if r.policy == policy]
        style = {"color": colours[policy], "marker": "o", "markersize": MARKER_SIZE, "linewidth": 1.0}
        k = [int(r.split) + shift for r in own]
        left.plot(k, [r.success for r in own], label=policy, **style)
        right.plot(k, [r.cost_ratio for r in own], **style)  # NaN (nothing solved) breaks the line
        bars = {"ecolor": colours[policy], "elinewidth": 1.0, "capsize": 2}
        success = [_interval(r.success, r.success_low, r.success_high) for r in own]
        _error_bars(left, list(zip(k, [r.success for r in own], success, strict=True)), **bars)
        ratio = [_interval(r.cost_ratio, r.cost_ratio_low, r.cost_ratio_high) for r in own]
        _error_bars(right, list(zip(k, [r.cost_ratio for r in own], ratio, strict=True)), **bars)
    counts = sorted({int(r.split) for r in rows})
    for axis, label in ((left, "success rate (95 % CI)"), (right, "cost ratio to the reference (95 % CI)")):
        axis.set_xticks(counts)
        axis.set_xlabel("objects in the scenario" + (f" ({title})" if title else ""))
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    left.set_ylim(-0.02, 1.02)
    right.axhline(1.0, color="grey", linewidth=0.8)
    handles, labels = left.get_legend_handles_labels()
    figure.legend(handles, labels, loc="upper center", ncol=min(len(policies), 6), fontsize="small", frameon=False)
    caption = _caption(rows, bars=False, missing_interval=_missing_interval(rows))
    figure.text(0.5, 0.01, caption, ha="center", fontsize="x-small", wrap=True)
    figure.tight_layout(rect=(0, 0.05, 1, 1 - 0.06 * math.ceil(len(policies) / 6)))
    return figure


def plot_learning_curve(
    run_dir: str | Path, path: str | Path, columns: Sequence[str] | None = None, x: str | None = None
) -> Path:
    """A run folder's ``metrics.csv``: each numeric column (or ``columns``) against ``x`` (default: the first column).

    ``x="seconds"`` (or whatever column holds wall-clock time) draws the curves against time.
    A ``metrics.csv`` without rows, or without the column ``x``, is an :class:`InputError`.
    """
    with (Path(run_dir) / "metrics.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    if not rows:
        raise InputError(f"{Path(run_dir) / 'metrics.csv'} has no rows")
    x_key = x if x is not None else next(iter(rows[0]))
    if x_key not in rows[0]:
        raise InputError(f"{Path(run_dir) / 'metrics.csv'} has no column {x_key!r}")
    keys = list(columns) if columns is not None else [k for k in rows[0] if k != x_key and _numeric(rows, k)]
    plt = pyplot()
    figure, axes = plt.subplots(1, len(keys), figsize=(4 * len(keys), 3.2), squeeze=False)
    xs = [float(r[x_key]) for r in rows]
    for axis, key in zip(axes[0], keys, strict=True):
        axis.plot(xs, [float(r[key]) for r in rows], marker="o", markersize=MARKER_SIZE)  # one row shows too
        axis.set_xlabel(x_key)
        axis.set_ylabel(key)
    figure.suptitle(Path(run_dir).name)
    figure.tight_layout()
    figure.savefig(path, dpi=DPI)
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
    plt = pyplot()
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
    figure.savefig(path, dpi=DPI)
    plt.close(figure)
    return Path(path)


def plot_ppo_curves(curves: Sequence[tuple[str, Sequence[list[dict[str, float]]]]], path: str | Path) -> Path:
    """Held-out success, training success and return of PPO runs against env steps and wall-clock seconds, one PNG.

    ``curves`` holds, per baseline, its label and the ``metrics.csv`` rows of each of its
    runs (``steps``, ``seconds``, ``success``, ``return``, and ``heldout_success`` where the
    run was evaluated on held-out seeds: the rows without it, or with NaN, are left out of
    the top panels; an empty list for a run without metrics). One colour per baseline, one
    line per run, each point marked (a run with one row, as a smoke run has, is a dot); the
    legend names a baseline by its first run's line.
    """
    plt = pyplot()
    figure, axes = plt.subplots(3, 2, figsize=(10, 10), squeeze=False)
    colours = policy_colours([label for label, _ in curves])
    for label, runs in curves:
        for j, rows in enumerate(runs):
            for r, key in enumerate(("heldout_success", "success", "return")):
                shown = [row for row in rows if row.get(key, math.nan) == row.get(key, math.nan)]
                for c, x in enumerate(("steps", "seconds")):
                    if shown:
                        axes[r][c].plot(
                            [row[x] for row in shown],
                            [row[key] for row in shown],
                            color=colours[label],
                            alpha=0.8,
                            marker="o",
                            markersize=MARKER_SIZE,
                            label=label if j == 0 else None,
                        )  # fmt: skip  (markers: one row shows too)
    names = ("held-out success (seeds never trained on)", "training success (episodes of the rollout)",
             "return (learning reward)")  # fmt: skip
    for r, key in enumerate(names):
        for c, x in enumerate(("env steps", "wall-clock seconds of training")):
            axes[r][c].set_xlabel(x)
            axes[r][c].set_ylabel(key)
            if r < 2:
                axes[r][c].set_ylim(-0.03, 1.03)  # success rates on one scale: 98 % does not look like a fall
    for r, c in ((0, 0), (1, 0)):
        if axes[r][c].get_legend_handles_labels()[0]:
            axes[r][c].legend(fontsize="small")
    figure.suptitle("MaskablePPO learning curves (one line per training seed)")
    figure.tight_layout()
    figure.savefig(path, dpi=DPI)
    plt.close(figure)
    return Path(path)
