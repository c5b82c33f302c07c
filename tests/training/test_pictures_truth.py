"""The pictures tell the truth: distinct object colours, close-ups that zoom, labels that stay with what they name,
legends, gallery pictures that match the code, honest error bars and captions, a notebook that says what the
tables compute. Every check reads the matplotlib artists (or a PNG's text), never pixels."""

from __future__ import annotations

import importlib.util
import itertools
import math
from dataclasses import replace
from pathlib import Path

import gymnasium as gym
import nbformat
import numpy as np
import pytest
from matplotlib import colors
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Rectangle
from PIL import Image

import fetchcarry_env  # noqa: F401  (registers FetchCarryPush-v0)
from expert.plot import TRAVEL
from fetchcarry_env import drawing
from fetchcarry_env.families import get_family
from fetchcarry_env.geometry import Rect
from fetchcarry_env.observation import WorldState, standing_center
from fetchcarry_env.scenario import Scenario
from training.evaluation.metrics import by_objects
from training.evaluation.splits import get_split
from training.pictures.episode import close_up_view, draw_episode, episode_steps
from training.rollout import EpisodeFigures, EpisodeRecord

ROOT = Path(__file__).resolve().parents[2]
MIN_DELTA_E = 25.0  # CIE76 colour difference two marks must keep (the old reds of the objects were 19 apart)


# ---------------------------------------------------------------------------- helpers
def lab(colour) -> np.ndarray:
    """CIE L*a*b* (D65) of a matplotlib colour: distances in it follow how different colours look."""
    rgb = np.array(colors.to_rgb(colour))
    linear = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]) @ linear
    f = np.cbrt(np.maximum(xyz / np.array([0.95047, 1.0, 1.08883]), (6 / 29) ** 3))
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def delta_e(a, b) -> float:
    return float(np.linalg.norm(lab(a) - lab(b)))


def map_axes(scenario: Scenario, view: Rect | None = None, width_in: float = 6.6):
    """A headless figure and its map axes of ``view`` (default: the area with its margin)."""
    figure = Figure(figsize=(width_in, width_in))
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    drawing.frame_map(axes, view or scenario.area.inflate(drawing.MARGIN))
    return figure, axes


def standing(scenario: Scenario, object_id: str, xy) -> tuple[float, float, float]:
    obj = next(o for o in scenario.objects if o.id == object_id)
    return standing_center(scenario, obj, xy)


def carry_every_object(scenario: Scenario) -> list[WorldState]:
    """States of an episode that carries each object from its start to its goal (bases beside them)."""
    states = [WorldState.initial(scenario)]
    for obj in scenario.objects:
        last = states[-1]
        beside_start = (obj.start[0] - 0.5, obj.start[1])
        picked = replace(last, base=beside_start, holding=obj.id)
        moved = replace(picked, base=(obj.goal[0] - 0.5, obj.goal[1]))
        objects = {**moved.objects, obj.id: standing(scenario, obj.id, obj.goal)}
        states += [replace(last, base=beside_start), picked, moved, replace(moved, holding=None, objects=objects)]
    return states


def push_then_place(scenario: Scenario) -> list[WorldState]:
    """The example's story, by hand: fetch the bottle, push the block off its goal, place the bottle."""
    start = WorldState.initial(scenario)
    near = replace(start, base=(1.45, 2.0), heading="+x")
    held = replace(near, holding="bottle")
    at_goal = replace(held, base=(3.45, 4.0))
    pushed = replace(at_goal, base=(3.45, 4.12), clutter={"block": (4.0, 4.12)})
    placed = replace(pushed, holding=None, objects={"bottle": standing(scenario, "bottle", (4.0, 3.93))})
    return [start, near, held, at_goal, pushed, placed]


def record_of(scenario: Scenario, states: list[WorldState]) -> EpisodeRecord:
    """An episode record of ``states`` with blank renders (what a still picture needs of it)."""
    steps = len(states) - 1
    figures = EpisodeFigures(
        seed=0, scenario=scenario.name, objects=len(scenario.objects), delivered=len(scenario.objects), success=True,
        outcome="delivered", failure=None, steps=steps, episode_return=1.0, path_length_m=10.0, collisions=0,
        invalid_actions=0, planning_s=0.1, policy_s=0.1, simulation_s=0.1, plans=1, replans=0, repairs=0,
        planner_failures=0, objective=None,
    )  # fmt: skip
    blank = np.full((240, 320, 3), 200, dtype=np.uint8)
    return EpisodeRecord(
        seed=0, scenario=scenario.to_dict(), observations={}, actions=np.zeros(steps, dtype=np.int64),
        rewards=np.zeros(steps), terminations=np.zeros(steps, bool), truncations=np.zeros(steps, bool), infos={},
        figures=figures, states=states, frames=[blank] * len(states),
    )  # fmt: skip


def apartment() -> Scenario:
    scenario = get_family("apartment").sample(np.random.default_rng(1))
    assert len(scenario.objects) == 5  # the picture the user found: five objects over three rooms
    return scenario


def display_box(axes, rect: Rect):
    """``rect`` (metres) in pixels on ``axes``' canvas."""
    from matplotlib.transforms import Bbox

    return Bbox(axes.transData.transform([rect.min, rect.max]))


# ---------------------------------------------------------------------------- colours
def test_every_object_has_its_own_colour_shared_by_its_goal_ring_and_label() -> None:
    scenario = apartment()
    _, axes = map_axes(scenario)
    drawing.draw_scenario(axes, scenario)
    discs, rings = {}, {}
    for patch in axes.patches:
        if not isinstance(patch, Circle):
            continue
        for obj in scenario.objects:
            if np.allclose(patch.center, obj.start) and patch.get_zorder() == drawing.Z_OBJECT:
                discs[obj.id] = patch.get_facecolor()
            if np.allclose(patch.center, obj.goal) and patch.radius == obj.radius and patch.get_facecolor()[3] == 0:
                rings[obj.id] = patch.get_edgecolor()
    labels = {t.get_text(): t.get_color() for t in axes.texts}
    assert set(discs) == set(rings) == {o.id for o in scenario.objects}
    for a, b in itertools.combinations(discs.values(), 2):
        assert delta_e(a, b) >= MIN_DELTA_E, (colors.to_hex(a), colors.to_hex(b))
    for object_id, face in discs.items():
        assert colors.to_hex(rings[object_id]) == colors.to_hex(face) == colors.to_hex(labels[object_id])


def test_up_to_eight_object_colours_stand_apart_from_each_other_and_from_the_other_marks() -> None:
    palette = drawing.PALETTE
    assert len(palette.objects) >= 8  # objects-8 draws eight
    for a, b in itertools.combinations(palette.objects, 2):
        assert delta_e(a, b) >= MIN_DELTA_E, (a, b)
    for colour in palette.objects:
        for other in (palette.clutter, palette.goal, TRAVEL):
            assert delta_e(colour, other) >= MIN_DELTA_E, (colour, other)


# ---------------------------------------------------------------------------- step labels
def test_step_numbers_at_one_place_share_one_label_written_as_a_range() -> None:
    scenario = apartment()
    _, axes = map_axes(scenario)
    points = [(0.0, 0.0), *[(3.0, 3.0)] * 4, (5.0, 1.0), (3.0, 3.0)]
    drawing.number_points(axes, points, merge_m=0.2, offset_m=0.1)
    assert sorted(t.get_text() for t in axes.texts) == ["0", "1-4,6", "5"]
    assert drawing.index_ranges([4, 16, 23, 24, 25]) == "4,16,23-25"


def test_no_two_step_labels_of_a_busy_episode_overlap() -> None:
    scenario = apartment()
    states = carry_every_object(scenario)
    states += [replace(states[-1], heading=h) for h in ("+y", "-x", "-y", "+x")]  # turns in place: one label
    figure, axes = map_axes(scenario)
    steps = episode_steps(states, np.zeros(len(states) - 1, dtype=np.int64))
    draw_episode(axes, scenario, states, steps, label_size_m=0.2 * scenario.area.size[0] / 6.6)
    figure.canvas.draw()
    drawing.separate_labels(axes)
    renderer = figure.canvas.get_renderer()
    numbers = [t for t in axes.texts if t.get_text()[:1].isdigit()]
    last = len(states) - 1  # carried there (last - 5), placed, turned four times: one label ending "19-24"
    assert any(t.get_text().endswith(f"{last - 5}-{last}") for t in numbers)
    boxes = [t.get_window_extent(renderer) for t in numbers]
    assert not any(a.overlaps(b) for a, b in itertools.combinations(boxes, 2))


# ---------------------------------------------------------------------------- clutter labels
def test_a_clutter_label_stays_on_or_touching_its_box(spec_example: Scenario) -> None:
    """The bottle placed right under the pushed block: their labels compete, the block's stays on its box."""
    states = push_then_place(spec_example)
    figure, axes = map_axes(spec_example)
    steps = episode_steps(states, np.zeros(len(states) - 1, dtype=np.int64))
    draw_episode(axes, spec_example, states, steps, label_size_m=0.2 * spec_example.area.size[0] / 6.6)
    figure.canvas.draw()
    drawing.separate_labels(axes)
    renderer = figure.canvas.get_renderer()
    block = next(c for c in spec_example.clutter if c.id == "block")
    end = Rect.around(states[-1].clutter["block"], block.rect.size[0] / 2, block.rect.size[1] / 2)
    label = next(t for t in axes.texts if t.get_text() == "block")
    assert label.get_window_extent(renderer).overlaps(display_box(axes, end).padded(1.0))
    bottle = next(t for t in axes.texts if t.get_text() == "bottle")  # the object's label too stays by its disc
    disc = Rect.around(states[-1].objects["bottle"][:2], 0.035, 0.035)
    assert bottle.get_window_extent(renderer).overlaps(display_box(axes, disc).padded(1.0))


# ---------------------------------------------------------------------------- close-ups
def test_the_close_up_zooms_on_where_the_pushes_and_places_are(spec_example: Scenario) -> None:
    states = push_then_place(spec_example)
    steps = episode_steps(states, np.zeros(len(states) - 1, dtype=np.int64))
    view = close_up_view(spec_example, steps)
    whole = spec_example.area.inflate(drawing.MARGIN)
    assert view is not None and max(view.size) <= 0.5 * min(spec_example.area.size)
    for point in (states[3].base, states[4].base, states[5].base, (4.0, 4.12), (4.0, 3.93)):
        assert view.contains_point(point)
    from training.pictures.episode import story_figure

    figure = story_figure(record_of(spec_example, states))
    close = next(a for a in figure.axes if a.get_title().startswith("close-up"))
    assert close.get_xlim() == pytest.approx((view.min_x, view.max_x))
    assert close.get_ylim() == pytest.approx((view.min_y, view.max_y))
    assert np.ptp(close.get_xlim()) < np.ptp((whole.min_x, whole.max_x))


def test_no_close_up_where_the_action_spreads_over_the_area() -> None:
    """Places in three rooms: a 'close-up' would be about the whole floor; none is drawn, the legend takes its place."""
    scenario = apartment()
    states = carry_every_object(scenario)
    steps = episode_steps(states, np.zeros(len(states) - 1, dtype=np.int64))
    assert close_up_view(scenario, steps) is None
    from training.pictures.episode import story_figure

    figure = story_figure(record_of(scenario, states))
    assert not [a for a in figure.axes if a.get_title().startswith("close-up")]
    assert any(a.get_legend() is not None for a in figure.axes)


def test_the_plan_and_scenario_plots_close_up_only_where_the_goal_tables_are_close(spec_example: Scenario) -> None:
    from expert.plot import _close_up_view

    spread = apartment()  # goals on tables in three rooms
    assert _close_up_view(spread, None) is None
    view = _close_up_view(spec_example, None)  # one goal table
    assert view is not None and max(view.size) <= 0.5 * min(spec_example.area.size)


# ---------------------------------------------------------------------------- the gallery
def test_the_gallery_pictures_have_a_legend_of_what_they_draw() -> None:
    from training.pictures.worlds import PICTURES, gallery_figure

    figure = gallery_figure(PICTURES["unseen-layouts"]())
    (legend,) = figure.legends
    labels = " | ".join(t.get_text() for t in legend.get_texts())
    for thing in ("robot start", "objects", "goal", "table", "wall", "clutter"):
        assert thing in labels


def test_the_perturbed_picture_shows_what_was_perturbed() -> None:
    from training.pictures.worlds import gallery_figure, perturbed_panel

    seed = 2
    panel = perturbed_panel(seed)
    assert panel.scenario.to_dict() == get_family("perturbed").sample(np.random.default_rng(seed)).to_dict()
    figure = gallery_figure([panel])
    whole, close = figure.axes[:2]
    dashed = [p.get_bbox().bounds for p in whole.patches if isinstance(p, Rectangle) and p.get_linestyle() == "--"]
    for table in panel.nominal.tables:  # the tables before the perturbation, dashed
        assert any(np.allclose(bounds, (*table.rect.min, *table.rect.size)) for bounds in dashed)
    assert panel.distractors() and "distractor" in " ".join(t.get_text() for t in figure.legends[0].get_texts())
    env = gym.make("FetchCarryPush-v0", family="perturbed")
    try:
        env.reset(seed=seed)
        physics = env.unwrapped._item_physics  # the masses and frictions the env drew for this episode
    finally:
        env.close()
    text = close.get_xlabel()
    for item_id, (mass, friction) in physics.items():
        assert f"{item_id[:16]:<16} {mass:4.2f} kg  {friction:4.2f}" in text


def test_the_committed_gallery_pictures_are_what_the_code_draws_now() -> None:
    """A stale picture (one drawn before a family changed: "2 obj" where the code draws 1) fails here.

    Each PNG carries its panels' titles, counts and scenario digests; the doc shows every picture.
    """
    from training.pictures.worlds import DESCRIPTION, PICTURES, describe

    page = (ROOT / "docs" / "families.md").read_text()
    for name, panels in PICTURES.items():
        path = ROOT / "docs" / "families" / f"{name}.png"
        with Image.open(path) as image:
            written = image.info.get(DESCRIPTION)
        assert written == describe(panels()), f"{path} is stale: python -m training.pictures.worlds docs/families"
        assert f"(families/{name}.png)" in page


# ---------------------------------------------------------------------------- benchmark plots
def outcome(policy: str, split: str, seed: int, objects: int, cost: float) -> dict:
    """One episode record as the benchmark writes it (this run's expert is the reference of a folder split)."""
    return {"policy": policy, "split": split, "source": f"objects-{objects}", "seed": seed, "objects": objects,
            "success": True, "delivered": objects, "cost": cost, "return": 1.0, "phases": 4, "pushes": 0,
            "invalid_actions": 0, "contacts": 0, "decision_ms": 1.0, "mask_ms": 0.5, "digest": f"d{seed}"}  # fmt: skip


def test_the_caption_lists_the_episode_counts_in_the_order_of_the_x_axis() -> None:
    """Six one-object episodes and two two-object ones (an iid run's mix): "6 (1), 2 (2)", not "2, 6"."""
    from training.pictures.benchmark import objects_figure, pyplot, splits_figure

    split = "scenarios:folder"
    records = [outcome(p, split, s, 1 if s < 6 else 2, 10.0 + s) for p in ("expert", "bc") for s in range(8)]
    for make in (lambda rows: splits_figure(rows, "objects in the scenario"), objects_figure):
        figure = make(by_objects(records))
        caption = " ".join(t.get_text() for t in figure.texts)
        pyplot().close(figure)
        assert "n = 6 (1), 2 (2) episodes per" in caption


def test_a_bar_without_an_interval_gets_no_error_bar_but_says_so() -> None:
    """One scenario per object count: the cost ratio has no interval; it was drawn with a bar of zero width."""
    from training.pictures.benchmark import NO_INTERVAL, objects_figure, pyplot, splits_figure

    split = "scenarios:folder"
    records = [outcome(p, split, k, k, 10.0 + (p == "bc")) for p in ("expert", "bc") for k in (1, 2, 3)]
    for make in (splits_figure, objects_figure):
        figure = make(by_objects(records))
        right = figure.axes[1]
        segments = [s for c in right.collections for s in getattr(c, "get_segments", list)()]
        marks = [t.get_text() for t in right.texts]
        caption = " ".join(t.get_text() for t in figure.texts)
        pyplot().close(figure)
        assert all(np.ptp(np.asarray(s)[:, 1]) > 0 for s in segments if len(s))  # no error bar of zero length
        assert marks.count(NO_INTERVAL) == 6 and NO_INTERVAL in caption  # each cost ratio says it has none


def test_long_split_names_under_the_bars_are_wrapped_and_read_back_whole() -> None:
    """Five splits of 24-29 characters overlapped under their bars (the perturbed factors' run)."""
    from training.pictures.benchmark import tick_label

    for name in ("perturbed-distractors-v2:test", "perturbed-physics-v2:test", "iid-v2:test", "scenarios:a-b:c"):
        lines = tick_label(name).split("\n")
        assert "".join(lines) == name and all(len(line) <= 16 for line in lines[1:] or lines)
    assert tick_label("iid-v2:test") == "iid-v2:test"


# ---------------------------------------------------------------------------- the benchmark notebook
def notebook_build():
    spec = importlib.util.spec_from_file_location("notebook_build", ROOT / "notebooks" / "build.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_benchmark_notebook_gives_the_score_and_the_splits_the_tables_use() -> None:
    build = notebook_build()
    text = "\n".join(cell.source for cell in build.BENCHMARK if cell.cell_type == "markdown")
    assert "0 for doing nothing" in text and "100 x sum(R - F) / sum(R_reference - F)" in text
    for name in ("iid", "more-objects", "layouts", "push-required", "objects", "apartment", "perturbed"):
        split = get_split(name)
        assert split.version_number == (3 if name == "layouts" else 2)  # the task cost's splits
        assert f"`{name}` (`{split.name}`): {split.description}" in text
    assert "T-junction" in get_split("layouts").description  # layouts is layouts-v3 (the unseen topologies)
    assert "refuses to score them" in text and "task cost" in text


def test_the_committed_notebooks_are_built_from_their_source() -> None:
    """A notebook edited in build.py but not rebuilt (python notebooks/build.py NAME) fails here."""
    build = notebook_build()
    for name, cells in build.NOTEBOOKS.items():
        committed = nbformat.read(ROOT / "notebooks" / name, as_version=4)
        assert [c.source for c in committed.cells] == [c.source for c in cells], name
        assert not any(o.get("output_type") == "error" for c in committed.cells for o in c.get("outputs", []))


def test_cost_ratio_intervals_are_missing_only_below_two_scenarios() -> None:
    """What the "no CI" mark relies on: one scenario has no interval, two have one."""
    split = "scenarios:folder"
    one = by_objects([outcome(p, split, 1, 1, 10.0 + (p == "bc")) for p in ("expert", "bc")])
    two = by_objects([outcome(p, split, s, 1, 10.0 + s * (p == "bc")) for p in ("expert", "bc") for s in (1, 2)])
    assert math.isnan(next(r for r in one if r.policy == "bc").cost_ratio_low)
    assert not math.isnan(next(r for r in two if r.policy == "bc").cost_ratio_low)
