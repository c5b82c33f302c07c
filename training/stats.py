"""Interval estimates of success rates: the Wilson score interval, used by every evaluation.

Pure arithmetic (no env, no policy), so that learners measuring their held-out success
and the benchmark's metrics share one definition.
"""

from __future__ import annotations

import math

Z_95 = 1.96  # the normal quantile of a two-sided 95 % interval


def wilson(successes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """The Wilson score interval of a success rate (95 % with the default ``z``)."""
    if n == 0:
        return (math.nan, math.nan)
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    # min/max with p: at 0 % or 100 % rounding can put an end a hair past p, which the interval contains
    return (min(p, max(0.0, centre - half)), max(p, min(1.0, centre + half)))
