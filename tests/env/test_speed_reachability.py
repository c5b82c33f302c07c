"""The families' reachability flood (``scipy.ndimage.label``) finds the cells a flood fill by dilation finds.

The two floods' speeds: ``python -m benchmarks.studies.reachability_flood``.
"""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.studies.reachability_flood import dilation_flood
from fetchcarry_env.families import FAMILY_NAMES, get_family
from fetchcarry_env.reachability import FreeSpace

DRAWS = 12  # scenarios drawn per family (before the family's checks: unworkable layouts included)


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
