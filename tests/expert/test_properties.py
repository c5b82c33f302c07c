"""Property: for random scenarios of every family the planner finds a plan, and the plan passes the validator.

Hypothesis draws the seed of each family's generator; a few examples per family keep
the suite fast (planning dominates). ``derandomize`` makes the drawn seeds the same on
every run, so a failure reproduces; the seed is in the failure report.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from expert.planner import plan
from expert.validate import validate_plan
from fetchcarry_env.families import FAMILY_NAMES, OBJECT_COUNTS, get_family

EXAMPLES_PER_FAMILY = 3
TIME_LIMIT = 20.0  # seconds per planning call: generous, the families' scenarios take well under a second or two
# The graded worlds beyond four objects, and the apartment, are where the planner is still slow: the expert
# plans objects-8 in physics 65 % of the time and apartment 30 % within 10 s (docs/benchmarks/worlds.md).
# They are the planner's open speed goals, measured by its benchmark, not a property every draw holds.
SLOW_FAMILIES = frozenset({*(f"objects-{k}" for k in OBJECT_COUNTS if k > 4), "apartment"})
PROPERTY_FAMILIES = tuple(name for name in FAMILY_NAMES if name not in SLOW_FAMILIES)


def test_every_family_is_covered():
    assert set(FAMILY_NAMES) >= {"basic", "push", "corridor", "multi", "mixed"}


@pytest.mark.parametrize("family_name", PROPERTY_FAMILIES)
@settings(
    max_examples=EXAMPLES_PER_FAMILY,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(seed=st.integers(min_value=0, max_value=2**32 - 1))
def test_random_scenarios_get_a_valid_plan(family_name, seed):
    scenario = get_family(family_name).sample(np.random.default_rng(seed))
    result = plan(scenario, time_limit=TIME_LIMIT)
    assert result.status in ("optimal", "feasible"), (family_name, seed, result.status, result.stats)
    assert result.scenario == scenario.name
    assert validate_plan(scenario, result) == [], (family_name, seed)
