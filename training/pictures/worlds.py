"""Pictures of the graded worlds for ``docs/families.md``: a few seeds of a family, side by side, from above.

``python -m training.pictures.worlds OUT_DIR`` writes one PNG per picture of
:data:`PICTURES` (matplotlib, headless, :mod:`fetchcarry_env.drawing`), each with a
legend of what is drawn. The ``perturbed`` picture shows what was perturbed: the tables
and the start before the perturbation (dashed), the distractors ringed, and under each
scenario a close-up of one table with the clutter's mass and friction as the env draws
them at ``reset(seed=...)``.

Every PNG carries :func:`describe` of its panels (their titles and their scenarios'
digests) in its ``Description`` text: a test compares the committed pictures with what
the code draws now, so that a picture left stale by a change of a family fails it.
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch

from fetchcarry_env import drawing
from fetchcarry_env.families import draw_training, get_family
from fetchcarry_env.reachability import unreachable_targets
from fetchcarry_env.scenario import Scenario, Table, check_rules
from fetchcarry_env.worlds.perturbed import perturb
from fetchcarry_env.worlds.physics import ItemPhysics
from fetchcarry_env.worlds.unseen import LAYOUTS, draw_unseen

PANEL_IN = 3.2  # inches per panel: its width, and its map's height
TITLE_IN = 0.5  # inches of a panel's title and tick labels, above and under its map
PHYSICS_IN = 0.9  # inches of a perturbed close-up's text under it
LEGEND_IN = 0.6  # inches of the legend under the panels
DPI = 120
CLOSE_UP_MARGIN = 0.2  # metres shown around a perturbed table in its close-up
DISTRACTOR_RING = 0.18  # metres: the radius of the ring around a distractor in the whole view
BEFORE_STYLE = {"linestyle": "--", "linewidth": 1.0}  # the outline of a table or the start before the perturbation
DESCRIPTION = "Description"  # the PNG text key that holds describe(panels)


@dataclass(frozen=True)
class Panel:
    """One scenario of a picture; a perturbed one with the scenario before the perturbation and its physics."""

    title: str
    scenario: Scenario
    nominal: Scenario | None = None  # the scenario before perturb(): same ids, tables and start unmoved
    physics: Mapping[str, ItemPhysics] = field(default_factory=dict)  # clutter id -> mass (kg), friction

    def distractors(self) -> list[str]:
        """Ids of the clutter the perturbation added (none without a nominal scenario)."""
        if self.nominal is None:
            return []
        before = {item.id for item in self.nominal.clutter}
        return [item.id for item in self.scenario.clutter if item.id not in before]

    def counts(self) -> str:
        """``"2 obj, 3 tables, 2 clutter"`` (and how many of the clutter are distractors)."""
        scenario = self.scenario
        text = f"{len(scenario.objects)} obj, {len(scenario.tables)} tables, {len(scenario.clutter)} clutter"
        added = len(self.distractors())
        return text + (f" ({added} distractor{'s' if added > 1 else ''})" if added else "")


# ---------------------------------------------------------------------------- the panels of each picture
def _objects() -> list[Panel]:
    return [_sampled(f"objects-{k}", 0, f"objects-{k}, seed 0") for k in range(1, 9)]


def _family(name: str, seeds: range) -> list[Panel]:
    return [_sampled(name, s, f"{name}, seed {s}") for s in seeds]


def _sampled(family: str, seed: int, title: str) -> Panel:
    return Panel(title, get_family(family).sample(np.random.default_rng(seed)))


def _unseen() -> list[Panel]:
    panels = []
    for layout in LAYOUTS:
        for seed in range(50):
            scenario = draw_unseen(np.random.default_rng(seed), layout)
            if get_family("unseen-layouts").capacity.fits(scenario) and _workable(scenario):
                panels.append(Panel(f"{layout} (seed {seed})", scenario))
                break
    return panels


def _workable(scenario: Scenario) -> bool:
    return not check_rules(scenario) and not unreachable_targets(scenario)


def _perturbed() -> list[Panel]:
    return [perturbed_panel(seed) for seed in range(4)]


def perturbed_panel(seed: int) -> Panel:
    """``perturbed``'s scenario of ``seed`` (as ``reset(seed=seed)`` draws it), the one before it, and its physics.

    The family is sampled with a draw that keeps the ``training`` scenario it perturbs
    (``draw_perturbed``'s own steps, so the same generator gives the same scenario); the
    physics are drawn from the same generator next, as the env does at reset.
    """
    family = get_family("perturbed")
    before: list[Scenario] = []

    def draw(rng: np.random.Generator) -> Scenario:
        before.append(draw_training(rng))
        return perturb(rng, before[-1])

    rng = np.random.default_rng(seed)
    scenario = replace(family, draw=draw).sample(rng)
    physics = family.physics.draw(rng, scenario) if family.physics is not None else {}
    return Panel(f"perturbed, seed {seed}", scenario, before[-1], physics)


PICTURES = {
    "objects-k": _objects,
    "apartment": lambda: _family("apartment", range(4)),
    "unseen-layouts": _unseen,
    "perturbed": _perturbed,
}


# ---------------------------------------------------------------------------- drawing
def gallery_figure(panels: list[Panel], columns: int = 4) -> Figure:
    """The scenarios of ``panels`` on a grid of ``columns``, each on the shared extent, a legend under them.

    A panel with a nominal scenario (``perturbed``) shows what was perturbed, and a row under it holds its close-up.
    """
    perturbed = any(panel.nominal is not None for panel in panels)
    heights = [PANEL_IN + TITLE_IN, *([PANEL_IN + PHYSICS_IN] if perturbed else [])] * math.ceil(len(panels) / columns)
    figure = Figure(figsize=(PANEL_IN * columns, sum(heights) + LEGEND_IN), layout="constrained")
    FigureCanvasAgg(figure)
    grid = figure.add_gridspec(len(heights), columns, height_ratios=heights)
    for k, panel in enumerate(panels):
        row, column = (k // columns) * (2 if perturbed else 1), k % columns
        axes = figure.add_subplot(grid[row, column])
        _draw_panel(axes, panel)
        if panel.nominal is not None:
            _draw_close_up(figure.add_subplot(grid[row + 1, column]), panel)
    handles, labels = drawing.scene_legend(
        max(len(p.scenario.objects) for p in panels),
        obstacles=any(p.scenario.obstacles for p in panels),
        clutter=any(p.scenario.clutter for p in panels),
    )
    if perturbed:
        clutter_before = any(p.nominal is not None and p.nominal.clutter for p in panels)
        entries = [entry for entry in _before_entries() if clutter_before or entry[1] != CLUTTER_BEFORE]
        handles, labels = handles + [h for h, _ in entries], labels + [label for _, label in entries]
    figure.legend(handles, labels, handler_map=drawing.LEGEND_HANDLERS, loc="outside lower center",
                  ncol=min(len(labels), 5), fontsize=8, frameon=False, handlelength=3.5)  # fmt: skip
    return figure


def _draw_panel(axes: Axes, panel: Panel) -> None:
    """One scenario on the shared extent, titled with its counts; what was perturbed, if it was."""
    drawing.frame_map(axes, get_family("basic").extent.inflate(0.1))
    drawing.draw_scenario(axes, panel.scenario, show_labels=False)
    if panel.nominal is not None:
        _draw_before(axes, panel)
        for item in panel.scenario.clutter:
            if item.id in panel.distractors():
                axes.add_patch(Circle(item.rect.center, DISTRACTOR_RING, facecolor="none", edgecolor="black",
                                      linewidth=0.8, zorder=drawing.Z_TEXT))  # fmt: skip
    axes.set_title(f"{panel.title}\n{panel.counts()}", fontsize=8)
    axes.tick_params(labelsize=6)
    axes.set_xlabel("")
    axes.set_ylabel("")


def _draw_before(axes: Axes, panel: Panel) -> None:
    """The tables and the start of the scenario before the perturbation, dashed."""
    nominal, edge = panel.nominal, drawing.PALETTE.robot_edge
    for table in nominal.tables:
        drawing.draw_rect(axes, table.rect, face="none", edge=edge, zorder=drawing.Z_OBJECT + 0.5, **BEFORE_STYLE)
    start = Circle(nominal.robot.start, nominal.robot.radius, facecolor="none", edgecolor=edge, **BEFORE_STYLE)
    start.set_zorder(drawing.Z_ROBOT + 0.5)
    axes.add_patch(start)


def _draw_close_up(axes: Axes, panel: Panel) -> None:
    """The table with a distractor (else the one moved most), before and after, with the clutter's physics below."""
    table, moved_m = _shown_table(panel)
    before = next(t for t in panel.nominal.tables if t.id == table.id)
    view = drawing.close_up([table.rect, before.rect], table.rect, CLOSE_UP_MARGIN, most=math.inf)
    drawing.frame_map(axes, view)
    drawing.draw_scenario(axes, panel.scenario, show_robot=False)
    for item in panel.nominal.clutter:
        drawing.draw_clutter(axes, item, item.rect.center, ghost=True)
    _draw_before(axes, panel)
    axes.set_title(f"close-up: {table.id} moved {100 * moved_m:.1f} cm", fontsize=8)
    axes.tick_params(labelsize=6)
    axes.set_ylabel("")
    axes.set_xlabel(_physics_text(panel), fontsize=6.5, family="monospace", loc="left")
    axes.figure.canvas.draw()
    drawing.separate_labels(axes)


def _shown_table(panel: Panel) -> tuple[Table, float]:
    """The table to show close: the first distractor's, else the one moved most; and how far it moved (metres)."""
    pairs = zip(panel.scenario.tables, panel.nominal.tables, strict=True)
    moves = {table.id: math.dist(table.rect.min, before.rect.min) for table, before in pairs}
    distractors = [c for c in panel.scenario.clutter if c.id in panel.distractors()]
    holding = [t for t in panel.scenario.tables if distractors and t.rect.contains_rect(distractors[0].rect)]
    table = holding[0] if holding else max(panel.scenario.tables, key=lambda t: moves[t.id])
    return table, moves[table.id]


def _physics_text(panel: Panel) -> str:
    """Lines under a perturbed close-up: how far the start moved, then each piece of clutter's mass and friction."""
    start_m = math.dist(panel.scenario.robot.start, panel.nominal.robot.start)
    lines = [f"start moved {100 * start_m:.1f} cm", "clutter: mass, friction at reset"]
    for item in panel.scenario.clutter:
        mass, friction = panel.physics[item.id]
        lines.append(f" {item.id[:16]:<16} {mass:4.2f} kg  {friction:4.2f}")
    return "\n".join(lines)


CLUTTER_BEFORE = "clutter before it"  # the legend's entry of the clutter's place before the perturbation


def _before_entries() -> list[tuple[object, str]]:
    """Legend samples and labels of what the perturbed picture adds."""
    palette = drawing.PALETTE
    return [
        (Patch(facecolor="none", edgecolor=palette.robot_edge, **BEFORE_STYLE), "table, start before the perturbation"),
        (Patch(facecolor="none", edgecolor=palette.clutter_edge, linestyle="--"), CLUTTER_BEFORE),
        (Line2D([], [], marker="o", markersize=10, fillstyle="none", color="black", linestyle="none"), "distractor"),
    ]


# ---------------------------------------------------------------------------- files
def describe(panels: list[Panel]) -> str:
    """One line per panel: its title, its counts and its scenario's digest (what a picture's PNG must carry)."""
    return "\n".join(f"{p.title}: {p.counts()} [{_digest(p.scenario)}]" for p in panels)


def _digest(scenario: Scenario) -> str:
    """The first 16 hex digits of the sha256 of ``scenario``'s canonical JSON."""
    return hashlib.sha256(json.dumps(scenario.to_dict(), sort_keys=True).encode()).hexdigest()[:16]


def draw_panels(panels: list[Panel], path: Path, columns: int = 4) -> Path:
    """Write :func:`gallery_figure` of ``panels`` to ``path`` (PNG), with :func:`describe` in its text."""
    path.parent.mkdir(parents=True, exist_ok=True)
    gallery_figure(panels, columns).savefig(path, dpi=DPI, metadata={DESCRIPTION: describe(panels)})
    return path


def main(out: str) -> None:
    for name, panels in PICTURES.items():
        print(draw_panels(panels(), Path(out) / f"{name}.png"))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/families")
