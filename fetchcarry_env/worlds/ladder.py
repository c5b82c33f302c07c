"""``objects-1-4``: an ``objects-k`` scenario with k drawn uniformly in 1 .. 4 (the ladder's training family).

The ladder (``docs/ladder.md``) trains a learner on ``objects-1`` to ``objects-4`` only
and tests it on ``objects-1`` to ``objects-8``. ``fetchcarry train bc`` reads one dataset,
so its demonstrations come from this one family: each scenario first draws k from the
same generator, then the ``objects-k`` scenario (:func:`fetchcarry_env.worlds.objects.draw_objects`).
"""

from __future__ import annotations

import numpy as np

from fetchcarry_env.scenario import Scenario
from fetchcarry_env.worlds.objects import draw_objects

LADDER_COUNTS = (1, 4)  # the fewest and most objects the training family draws, inclusive


def draw_ladder(rng: np.random.Generator) -> Scenario:
    """An ``objects-k`` scenario, k uniform in :data:`LADDER_COUNTS` (inclusive), all drawn from ``rng``."""
    low, high = LADDER_COUNTS
    return draw_objects(rng, int(rng.integers(low, high + 1)))
