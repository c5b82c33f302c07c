"""A plan drawn from above, like the paper's figures: the base path phase by phase.

:func:`plot_plan` draws the scenario (tables, obstacles, clutter where it started and
where it was pushed to, objects and their goals), then the plan: every base move as
an arrow (travel with an empty hand, carrying, push strokes), the base disc and its
heading at every phase with the phase number, the arm line of every pick and place,
and a list of the steps beside the map. The title carries the status and the
objective. :func:`plot_scenario` draws a scenario alone as it starts, in the same
layout (what it holds beside the map, a close-up of the goal tables), without
planning. Headless (Agg); see :mod:`fetchcarry_env.drawing` for the shared pieces.
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from expert.plans import Phase, Plan, phase_rows, plan_length
from fetchcarry_env import drawing
from fetchcarry_env.geometry import Point, Rect
from fetchcarry_env.scenario import Scenario

# Colours of the plan's own marks (the scene's colours are drawing.PALETTE).
TRAVEL = "#505050"  # a move with an empty hand
CARRY = drawing.PALETTE.object  # a move holding the first object (each object has its colour)
PUSH = drawing.PALETTE.clutter  # a push stroke, in the clutter's colour
PICK = "#1f9e89"  # teal: not the goals' green
PLACE = "#9467bd"

SIDE_WIDTH_IN = 3.6  # inches of the column beside the map (steps and the close-up)
MAX_LISTED_STEPS = 30  # longer plans list their first steps only
STEP_ROW_IN = 0.125  # inches per row of the step list (7 pt monospace)
MIN_CLOSE_UP_IN = 3.0  # inches of height kept for the close-up
CLOSE_UP_MARGIN = 0.45  # metres shown around the close-up's content
LABEL_SIZE_IN = 0.2  # inches: phase numbers closer than this on the page share one label
LABEL_OFFSET = 0.75  # phase numbers sit this many base radii left of and above the base centre


def plot_plan(scenario: Scenario, plan: Plan, path: str | Path, *, width_in: float = 7.0, dpi: int = 120) -> Path:
    """Draw ``plan`` for ``scenario`` from above and save it (PNG, SVG, PDF: by the suffix of ``path``).

    Left: the whole area with the plan. Right: the list of steps and a close-up of
    where objects are placed and clutter pushed. A plan without phases (no plan found)
    draws the scenario with the status in the title. Returns the path written.
    """
    path = Path(path)
    height_in = drawing.map_height_in(scenario, width_in) + 1.1  # title, axis labels and the legend
    figure = Figure(figsize=(width_in + SIDE_WIDTH_IN, height_in), layout="constrained")
    FigureCanvasAgg(figure)
    listed = min(len(plan.phases), MAX_LISTED_STEPS) + 4  # text rows of the step list
    steps_in = min(STEP_ROW_IN * listed + 0.2, height_in - MIN_CLOSE_UP_IN)
    grid = figure.add_gridspec(
        2, 2, width_ratios=[width_in, SIDE_WIDTH_IN], height_ratios=[steps_in, height_in - steps_in]
    )
    map_axes = figure.add_subplot(grid[:, 0])
    steps_axes = figure.add_subplot(grid[0, 1])
    close_axes = figure.add_subplot(grid[1, 1])
    close_axes.set_anchor("N")  # an equal-aspect map: keep it just under the step list

    view = scenario.area.inflate(drawing.MARGIN)
    drawing.frame_map(map_axes, view)
    _draw_plan(map_axes, scenario, plan, label_merge_m=LABEL_SIZE_IN * view.size[0] / width_in)
    figure.legend(handles=_legend_handles(scenario), loc="outside lower center", ncol=5, fontsize=7, frameon=False)
    map_axes.set_title(_title(scenario, plan), fontsize=10)
    _list_steps(steps_axes, plan)
    close_view = _close_up_view(scenario, plan)
    if close_view is None:
        _no_close_up(close_axes, "the goal tables, places and pushes")
    else:
        drawing.frame_map(close_axes, close_view)
        _draw_plan(close_axes, scenario, plan, label_merge_m=LABEL_SIZE_IN * close_view.size[0] / SIDE_WIDTH_IN)
        close_axes.set_title("close-up: places and pushes", fontsize=9)
    figure.canvas.draw()  # lays the figure out, so that labels are separated where they will be
    drawing.separate_labels(map_axes)
    drawing.separate_labels(close_axes)
    figure.savefig(path, dpi=dpi)
    return path


def _draw_plan(axes: Axes, scenario: Scenario, plan: Plan, *, label_merge_m: float) -> None:
    """The scene and every mark of the plan on one map."""
    phases = plan.phases
    drawing.draw_scenario(axes, scenario, show_robot=not phases, show_clutter=False)
    _draw_clutter(axes, scenario, phases)
    for phase in phases:
        drawing.draw_faint_base(axes, phase.base, phase.heading, scenario.robot.radius)
    for k in range(1, len(phases)):
        _draw_step(axes, scenario, phases[k - 1], phases[k])
    drawing.number_points(axes, [p.base for p in phases], label_merge_m, LABEL_OFFSET * scenario.robot.radius)


def _close_up_view(scenario: Scenario, plan: Plan | None) -> Rect | None:
    """The region around the goal tables and the bases of every place and push (and where pushes start).

    None where that region is most of the area (:func:`fetchcarry_env.drawing.close_up`): no close-up then.
    """
    boxes = [t.rect for obj in scenario.objects if (t := scenario.table_under(obj.goal, obj.radius)) is not None]
    for k, phase in enumerate(plan.phases if plan is not None else ()):
        if phase.action in ("place", "push"):
            boxes.append(drawing.point_box(phase.base))
            if phase.action == "push":
                boxes.append(drawing.point_box(plan.phases[k - 1].base))
    return drawing.close_up(boxes, scenario.area.inflate(drawing.MARGIN), CLOSE_UP_MARGIN)


def _no_close_up(axes: Axes, what: str) -> None:
    """The close-up's place where none is drawn: why (``what`` spreads over most of the area)."""
    axes.set_axis_off()
    axes.text(0.0, 1.0, f"no close-up: {what}\nspread over most of the area", va="top", fontsize=8,
              transform=axes.transAxes)  # fmt: skip


def _draw_clutter(axes: Axes, scenario: Scenario, phases: tuple[Phase, ...]) -> None:
    """Clutter where it ends, with a dashed outline where it started if it was pushed."""
    last = phases[-1] if phases else None
    for item in scenario.clutter:
        end = last.clutter.get(item.id, item.rect.center) if last else item.rect.center
        moved = abs(end[0] - item.rect.center[0]) > 1e-9 or abs(end[1] - item.rect.center[1]) > 1e-9
        if moved:
            drawing.draw_clutter(axes, item, item.rect.center, ghost=True)
        drawing.draw_clutter(axes, item, end)


def _draw_step(axes: Axes, scenario: Scenario, before: Phase, after: Phase) -> None:
    """The base move into ``after`` and what the arm does at its end."""
    if after.action == "push":
        drawing.draw_arrow(axes, before.base, after.base, PUSH, width=3.0)
        if after.target in before.clutter and after.target in after.clutter:
            drawing.draw_arrow(
                axes, before.clutter[after.target], after.clutter[after.target], PUSH, width=1.5, style="->"
            )
        return
    colour = TRAVEL if before.holding is None else drawing.object_colour(scenario, before.holding)
    drawing.draw_arrow(axes, before.base, after.base, colour, width=1.6)
    if after.action in ("pick", "place") and after.target is not None:
        state = before if after.action == "pick" else after
        target = state.objects.get(after.target)
        if target is not None:
            colour = PICK if after.action == "pick" else PLACE
            draw_arm(axes, after.base, target, colour, after.action, drawing.object_colour(scenario, after.target))


def draw_arm(axes: Axes, base: Point, hand: Point, colour: str, action: str, object_colour: str) -> None:
    """The arm line of a pick or place and a marker at the hand.

    Triangle up: pick, down: place; the edge is the action's colour, the fill the object's.
    """
    axes.plot([base[0], hand[0]], [base[1], hand[1]], color=colour, linestyle=":", linewidth=1.8, zorder=drawing.Z_TEXT)
    axes.plot(
        [hand[0]],
        [hand[1]],
        marker="^" if action == "pick" else "v",
        markersize=9,
        markerfacecolor=object_colour,
        markeredgecolor=colour,
        markeredgewidth=1.8,
        linestyle="none",
        zorder=drawing.Z_TEXT,
    )


def path_legend_handles(scenario: Scenario, base_label: str, object_label: str) -> list:
    """Legend entries of a drawn path: moves, pushes, picks, places, base poses and each object (``object_label``)."""
    palette = drawing.PALETTE
    handles = [
        Line2D([], [], color=TRAVEL, linewidth=1.6, marker=">", label="move, hand empty"),
        Line2D([], [], color=CARRY, linewidth=1.6, marker=">", label="move, carrying (object's colour)"),
        Line2D([], [], color=PUSH, linewidth=3.0, marker=">", label="push stroke"),
        Line2D([], [], color=PICK, linestyle=":", marker="^", markerfacecolor="white", label="pick (arm line)"),
        Line2D([], [], color=PLACE, linestyle=":", marker="v", markerfacecolor="white", label="place (arm line)"),
        Patch(facecolor=palette.robot, edgecolor=palette.robot_edge, alpha=0.5, label=base_label),
    ]
    for obj in scenario.objects:
        colour = drawing.object_colour(scenario, obj.id)
        handles.append(Line2D([], [], color=colour, marker="o", linestyle="--", label=f"{obj.id}: {object_label}"))
    return handles


def _legend_handles(scenario: Scenario) -> list:
    palette = drawing.PALETTE
    handles = path_legend_handles(scenario, "base at phase k, heading", "start, goal ring")
    handles.append(Patch(facecolor=palette.table, edgecolor=palette.table_edge, label="table"))
    if scenario.obstacles:
        handles.append(Patch(facecolor=palette.obstacle, edgecolor=palette.wall, hatch="//", label="obstacle"))
    if scenario.clutter:
        handles.append(Patch(facecolor=palette.clutter, edgecolor=palette.clutter_edge, label="clutter (end)"))
        handles.append(Patch(facecolor="none", edgecolor=palette.clutter_edge, linestyle="--", label="clutter (start)"))
    return handles


def _title(scenario: Scenario, plan: Plan) -> str:
    objective = "n/a" if plan.objective is None else f"{plan.objective:.3f}"
    length = plan_length(len(plan.phases)) if plan.phases else "no phases"
    total_s = plan.stats.get("total_s")
    timing = f", {total_s:.2f} s" if isinstance(total_s, int | float) else ""
    return f"{scenario.name}: {plan.status}, objective {objective}, {length}{timing}"


def _step_row(k: int, phase: Phase) -> str:
    base = f"{phase.base[0]:5.2f}, {phase.base[1]:5.2f}"
    target, posture = (phase.target or "-")[:10], (phase.posture or "-")[:10]
    return f"{k:>2} {phase.action:<6} {target:<10} {posture:<10} {base:<14} {phase.heading}"


def _list_steps(axes: Axes, plan: Plan) -> None:
    """The phases as a text table: number, action, target, posture, base and heading."""
    axes.set_axis_off()
    if not plan.phases:
        axes.text(0.0, 1.0, f"no plan ({plan.status})", va="top", fontsize=9, transform=axes.transAxes)
        return
    rows = [
        "steps (phase 0 is the start)",
        "",
        f"{'k':>2} {'action':<6} {'target':<10} {'posture':<10} {'base [m]':<14} hd",
    ]
    rows += phase_rows(plan, _step_row, MAX_LISTED_STEPS, "   ... and {} more phases")
    axes.text(0.0, 1.0, "\n".join(rows), va="top", ha="left", family="monospace", fontsize=7, transform=axes.transAxes)


def plot_scenario(scenario: Scenario, path: str | Path, *, width_in: float = 7.0, dpi: int = 120) -> Path:
    """Draw ``scenario`` from above as it starts and save it (PNG, SVG, PDF: by the suffix of ``path``); no plan.

    Left: the whole area (tables, obstacles, clutter, objects, goals, the robot, each
    labelled). Right: what the scenario holds, and a close-up of the goal tables, where a
    goal under clutter shows (the goals are drawn above the clutter). Returns the path written.
    """
    path = Path(path)
    height_in = drawing.map_height_in(scenario, width_in) + 1.1  # title, axis labels and the legend
    figure = Figure(figsize=(width_in + SIDE_WIDTH_IN, height_in), layout="constrained")
    FigureCanvasAgg(figure)
    facts = _scenario_facts(scenario)
    facts_in = min(STEP_ROW_IN * (len(facts) + 1) + 0.2, height_in - MIN_CLOSE_UP_IN)
    grid = figure.add_gridspec(
        2, 2, width_ratios=[width_in, SIDE_WIDTH_IN], height_ratios=[facts_in, height_in - facts_in]
    )
    map_axes = figure.add_subplot(grid[:, 0])
    facts_axes = figure.add_subplot(grid[0, 1])
    close_axes = figure.add_subplot(grid[1, 1])
    close_axes.set_anchor("N")
    drawing.frame_map(map_axes, scenario.area.inflate(drawing.MARGIN))
    close_view = _close_up_view(scenario, None)
    maps = [map_axes]
    if close_view is None:
        _no_close_up(close_axes, "the goal tables")
    else:
        drawing.frame_map(close_axes, close_view)
        close_axes.set_title("close-up: the goal tables", fontsize=9)
        maps.append(close_axes)
    for axes in maps:
        drawing.draw_scenario(axes, scenario, show_clutter=False)
        for item in scenario.clutter:  # labelled above, so that the label does not hide a goal under it
            drawing.draw_clutter(axes, item, item.rect.center, label=False)
            drawing.box_label(axes, item.rect, item.id, color=drawing.PALETTE.clutter_edge, weight="bold", side="above")
    map_axes.set_title(f"{scenario.name}: the scenario as it starts (no plan)", fontsize=10)
    facts_axes.set_axis_off()
    facts_axes.text(0.0, 1.0, "\n".join(facts), va="top", ha="left", family="monospace", fontsize=7,
                    transform=facts_axes.transAxes)  # fmt: skip
    figure.legend(handles=_scenario_legend_handles(scenario), loc="outside lower center", ncol=5, fontsize=7,
                  frameon=False)  # fmt: skip
    figure.canvas.draw()  # lays the figure out, so that labels are separated where they will be
    drawing.separate_labels(map_axes)
    drawing.separate_labels(close_axes)
    figure.savefig(path, dpi=dpi)
    return path


def _scenario_facts(scenario: Scenario) -> list[str]:
    """The text beside a scenario's map: the area, the robot, and every object with its tables."""
    area = scenario.area
    robot = scenario.robot
    rows = [
        f"area      x {area.min_x:g} to {area.max_x:g} m, y {area.min_y:g} to {area.max_y:g} m",
        f"robot     at ({robot.start[0]:g}, {robot.start[1]:g}), heading {robot.heading}, radius {robot.radius:g} m",
        f"holds     {len(scenario.tables)} table(s), {len(scenario.obstacles)} obstacle(s), "
        f"{len(scenario.clutter)} clutter",
        "",
        f"{'object':<10} {'start':<14} {'goal':<14} goal table",
    ]
    for obj in scenario.objects[:MAX_LISTED_STEPS]:
        table = scenario.table_under(obj.goal, obj.radius)
        start, goal = f"{obj.start[0]:.2f}, {obj.start[1]:.2f}", f"{obj.goal[0]:.2f}, {obj.goal[1]:.2f}"
        rows.append(f"{obj.id[:10]:<10} {start:<14} {goal:<14} {table.id if table else '-'}")
    if len(scenario.objects) > MAX_LISTED_STEPS:
        rows.append(f"... and {len(scenario.objects) - MAX_LISTED_STEPS} more objects")
    return rows


def _scenario_legend_handles(scenario: Scenario) -> list:
    """Legend entries of a scenario drawn as it starts."""
    palette = drawing.PALETTE
    handles = [Patch(facecolor=palette.robot, edgecolor=palette.robot_edge, alpha=0.8, label="robot start, heading")]
    for obj in scenario.objects[:6]:
        colour = drawing.object_colour(scenario, obj.id)
        handles.append(Line2D([], [], color=colour, marker="o", linestyle="--", label=f"{obj.id}: start, goal ring"))
    handles.append(Patch(facecolor=palette.goal, alpha=0.6, label="goal"))
    handles.append(Patch(facecolor=palette.table, edgecolor=palette.table_edge, label="table"))
    if scenario.obstacles:
        handles.append(Patch(facecolor=palette.obstacle, edgecolor=palette.wall, hatch="//", label="obstacle"))
    if scenario.clutter:
        handles.append(Patch(facecolor=palette.clutter, edgecolor=palette.clutter_edge, label="clutter"))
    return handles
