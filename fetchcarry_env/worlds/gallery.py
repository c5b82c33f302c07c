"""Pictures of the graded worlds for ``docs/families.md``: a few seeds of a family, side by side, from above.

``python -m fetchcarry_env.worlds.gallery OUT_DIR`` writes one PNG per picture of
:data:`PICTURES` (matplotlib, headless, :mod:`fetchcarry_env.drawing`).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from fetchcarry_env.drawing import draw_scenario, frame_map
from fetchcarry_env.families import get_family
from fetchcarry_env.reachability import unreachable_targets
from fetchcarry_env.scenario import Scenario, check_rules
from fetchcarry_env.worlds.unseen import LAYOUTS, draw_unseen

PANEL_IN = 3.2  # inches per panel


def _objects() -> list[tuple[str, Scenario]]:
    return [(f"objects-{k}, seed 0", get_family(f"objects-{k}").sample(np.random.default_rng(0))) for k in range(1, 9)]


def _family(name: str, seeds: range) -> list[tuple[str, Scenario]]:
    return [(f"{name}, seed {s}", get_family(name).sample(np.random.default_rng(s))) for s in seeds]


def _unseen() -> list[tuple[str, Scenario]]:
    panels = []
    for layout in LAYOUTS:
        for seed in range(50):
            scenario = draw_unseen(np.random.default_rng(seed), layout)
            if get_family("unseen-layouts").capacity.fits(scenario) and _workable(scenario):
                panels.append((f"{layout} (seed {seed})", scenario))
                break
    return panels


def _workable(scenario: Scenario) -> bool:
    return not check_rules(scenario) and not unreachable_targets(scenario)


def _perturbed() -> list[tuple[str, Scenario]]:
    return _family("perturbed", range(4))


PICTURES = {
    "objects-k": _objects,
    "apartment": lambda: _family("apartment", range(4)),
    "unseen-layouts": _unseen,
    "perturbed": _perturbed,
}


def draw_panels(panels: list[tuple[str, Scenario]], path: Path, columns: int = 4) -> Path:
    """The scenarios of ``panels`` (title, scenario) on a grid of ``columns``, each framed on the shared extent."""
    rows = (len(panels) + columns - 1) // columns
    figure = Figure(figsize=(PANEL_IN * columns, PANEL_IN * rows + 0.3), layout="constrained")
    FigureCanvasAgg(figure)
    for k, (title, scenario) in enumerate(panels):
        axes = figure.add_subplot(rows, columns, k + 1)
        frame_map(axes, get_family("basic").extent.inflate(0.1))
        draw_scenario(axes, scenario, show_labels=False)
        counts = f"{len(scenario.objects)} obj, {len(scenario.tables)} tables, {len(scenario.clutter)} clutter"
        axes.set_title(f"{title}\n{counts}", fontsize=8)
        axes.tick_params(labelsize=6)
        axes.set_xlabel("")
        axes.set_ylabel("")
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=120)
    return path


def main(out: str) -> None:
    for name, panels in PICTURES.items():
        print(draw_panels(panels(), Path(out) / f"{name}.png"))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/families")
