"""The reachability flood (``scipy.ndimage.label``) against the dilation flood it replaced: same cells, ms each.

    python -m benchmarks.studies.reachability_flood      # prints JSON

``tests/env/test_speed_reachability.py`` checks that the two agree on every family.
"""

from __future__ import annotations

import json
import time

import numpy as np

from fetchcarry_env.families import get_family
from fetchcarry_env.reachability import FreeSpace


def dilation_flood(free: np.ndarray, seed: tuple[int, int] | None) -> np.ndarray:
    """The reference: the free cells 4-connected to ``seed``, grown one ring at a time (the code it replaced)."""
    reached = np.zeros_like(free)
    if seed is None:
        return reached
    reached[seed] = True
    while True:
        grown = reached.copy()
        grown[1:, :] |= reached[:-1, :]
        grown[:-1, :] |= reached[1:, :]
        grown[:, 1:] |= reached[:, :-1]
        grown[:, :-1] |= reached[:, 1:]
        grown &= free
        if np.array_equal(grown, reached):
            return reached
        reached = grown


def compare(draws: int = 50, families: tuple[str, ...] = ("basic", "push", "corridor", "multi-2")) -> dict:
    """Both floods on ``draws`` scenarios of each family: how many agree cell for cell, and ms per scenario."""
    same = label_s = dilation_s = 0.0
    for family in families:
        rng = np.random.default_rng(1)
        for _ in range(draws):
            space = FreeSpace(get_family(family).draw(rng))
            seed = space._cell(space.scenario.robot.start, nearest_free=True)
            clock = time.perf_counter()
            labelled = space._flood(seed)
            label_s += time.perf_counter() - clock
            clock = time.perf_counter()
            dilated = dilation_flood(space.free, seed)
            dilation_s += time.perf_counter() - clock
            same += bool(np.array_equal(labelled, dilated))
    n = draws * len(families)
    return {"scenarios": n, "identical": int(same), "label_ms": 1e3 * label_s / n, "dilation_ms": 1e3 * dilation_s / n}


if __name__ == "__main__":
    print(json.dumps(compare(), indent=2))
