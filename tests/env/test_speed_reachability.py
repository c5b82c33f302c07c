"""The families' reachability flood (``scipy.ndimage.label``) finds the cells a flood fill by dilation finds."""

from __future__ import annotations

import numpy as np
import pytest

from fetchcarry_env.families import FAMILY_NAMES, get_family
from fetchcarry_env.reachability import FreeSpace

DRAWS = 12  # scenarios drawn per family (before the family's checks: unworkable layouts included)


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


@pytest.mark.parametrize("family", FAMILY_NAMES)
def test_label_flood_is_the_dilation_flood(family: str) -> None:
    rng = np.random.default_rng(7)
    for _ in range(DRAWS):
        space = FreeSpace(get_family(family).draw(rng))
        seed = space._cell(space.scenario.robot.start, nearest_free=True)
        assert np.array_equal(space.reached, dilation_flood(space.free, seed))


def test_flood_keeps_to_its_component() -> None:
    """A wall of blocked cells splits the grid: the flood stays on the start's side, as the dilation does."""
    space = FreeSpace(get_family("basic").draw(np.random.default_rng(0)))
    space.free = np.ones((9, 7), bool)
    space.free[4, :] = False
    space.free[6, 3] = False
    reached = space._flood((1, 1))
    assert np.array_equal(reached, dilation_flood(space.free, (1, 1)))
    assert reached[:4].all() and not reached[4:].any()
    assert not space._flood(None).any()


def compare(draws: int = 50, families: tuple[str, ...] = ("basic", "push", "corridor", "multi-2")) -> dict:
    """Both floods on ``draws`` scenarios of each family: how many agree cell for cell, and ms per scenario."""
    import time

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
    import json

    print(json.dumps(compare(), indent=2))
