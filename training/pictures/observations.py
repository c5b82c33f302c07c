"""The picture of the observation modes (docs/environment.md): one state seen as ``state``, ``topdown`` and ``rgbd``.

``python -m training.pictures.observations OUT.png`` runs the MILP expert on a ``push``
scenario until it holds the object, then draws, side by side: the world (the env's own
``rgb_array`` render: what the ``state`` vector describes), the ``topdown`` map (its
seven channels in colour, and each channel), and the head and overhead RGB-D images.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from expert.policy import ExpertPolicy
from fetchcarry_env.observations.topdown import CHANNELS
from training.envs import make_env

FAMILY, SEED = "push", 7  # a scenario whose goal is covered by a block (the demo's)
COLOURS = {  # RGB of each topdown channel in the composite
    "tables": (0.62, 0.45, 0.27),
    "obstacles": (0.45, 0.45, 0.50),
    "objects": (0.15, 0.35, 0.95),
    "goals": (0.10, 0.75, 0.25),
    "clutter": (0.95, 0.55, 0.10),
    "robot": (1.0, 1.0, 1.0),
    "held": (0.90, 0.10, 0.80),
}


def observed_state(family: str = FAMILY, seed: int = SEED) -> tuple[np.ndarray, dict[str, np.ndarray], int]:
    """The world's picture, its rgbd and topdown images once the expert holds the object, and the state's size."""
    env = make_env(family=family, obs_mode="rgbd", render_mode="rgb_array", width=480, height=360)
    observation, _ = env.reset(seed=seed)
    expert = ExpertPolicy(env)
    actions = []
    for _ in range(20):
        if env.unwrapped.state.holding is not None:
            break
        action, _ = expert.predict(observation, deterministic=True)
        observation, *_ = env.step(action)
        actions.append(action)
    world = env.render()
    env.close()
    topdown = make_env(family=family, obs_mode="topdown")  # the same episode, replayed
    mapped, _ = topdown.reset(seed=seed)
    for action in actions:
        mapped, *_ = topdown.step(action)
    topdown.close()
    return world, {**observation, "topdown": mapped["topdown"]}, int(observation["observation"].size)


def composite(topdown: np.ndarray) -> np.ndarray:
    """The map's channels painted over a black floor, each in its colour, opacity its value."""
    picture = np.zeros((*topdown.shape[1:], 3))
    for name, layer in zip(CHANNELS, topdown, strict=True):
        alpha = (layer / 255.0)[:, :, None]
        picture = picture * (1 - alpha) + alpha * np.array(COLOURS[name])
    return picture


def save_picture(path: str | Path) -> Path:
    """Draw the picture into ``path`` (PNG, PDF, SVG: matplotlib's formats)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    world, observation, size = observed_state()
    topdown = observation["topdown"]
    figure = plt.figure(figsize=(15, 5.2), constrained_layout=True)
    grid = figure.add_gridspec(2, 7, height_ratios=(2.2, 1))
    head, overhead = observation["head_rgbd"], observation["overhead_rgbd"]
    panels = [
        (world, f"state: {size} numbers\n(the world they describe)", None),
        (composite(topdown), f"topdown {topdown.shape[1]}x{topdown.shape[2]}\n7 channels in colour", None),
        (head[:3].transpose(1, 2, 0), f"rgbd head RGB {head.shape[1]}x{head.shape[2]}", None),
        (head[3], "head depth", "gray"),
        (overhead[:3].transpose(1, 2, 0), "rgbd overhead RGB", None),
        (overhead[3], "overhead depth", "gray"),
    ]
    spans = [(0, 2), (2, 3), (3, 4), (4, 5), (5, 6), (6, 7)]
    for (image, title, cmap), (a, b) in zip(panels, spans, strict=True):
        axes = figure.add_subplot(grid[0, a:b])
        axes.imshow(image, cmap=cmap, interpolation="nearest")
        axes.set_title(title, fontsize=10)
        axes.axis("off")
    for k, name in enumerate(CHANNELS):
        axes = figure.add_subplot(grid[1, k])
        axes.imshow(topdown[k], cmap="gray", vmin=0, vmax=255, interpolation="nearest")
        axes.set_title(f"topdown: {name}", fontsize=9)
        axes.axis("off")
    path = Path(path)
    figure.savefig(path, dpi=90)
    plt.close(figure)
    return path


if __name__ == "__main__":
    print(save_picture(sys.argv[1] if len(sys.argv) > 1 else "observations.png"))
