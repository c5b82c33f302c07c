"""The fewest-phases cuts (``expert.milp.fewest``) are exact: same status, phases and Eq. 1 with and without them.

Also what the action windows claim (``expert.milp.bounds.action_windows``): unions, not hulls.
"""

from __future__ import annotations

import numpy as np
import pytest

from expert.milp.bounds import PairCosts, action_windows, skeleton
from expert.milp.problem import prepare
from expert.planner import plan
from expert.validate import validate_plan
from fetchcarry_env import families
from fetchcarry_env.actions import Lattice


def _cases():
    rng = np.random.default_rng(7)
    cases = [families.draw_paper_basic(rng, area) for area in families.PAPER_AREAS]
    cases += [families.draw_paper_push(rng, pattern) for pattern in families.PUSH_PATTERNS]
    cases += [
        families.draw_paper_corridor(rng),
        families.draw_paper_multi(rng, 2),
        families.draw_paper_multi(rng, 2),
        families.draw_paper_multi(rng, 3),
    ]
    cases.append(families.draw_paper_covered(rng, 2))
    return cases


CASES = _cases()


@pytest.mark.parametrize("scenario", CASES, ids=[f"{k}-{s.name}" for k, s in enumerate(CASES)])
def test_the_cuts_keep_the_optimum(scenario):
    with_cuts = plan(scenario, time_limit=60)
    without = plan(scenario, time_limit=60, fewest_cuts=False)
    assert with_cuts.status == without.status == "optimal"
    assert len(with_cuts.phases) == len(without.phases)
    assert with_cuts.objective == pytest.approx(without.objective, abs=1e-6)
    assert validate_plan(scenario, with_cuts) == []
    assert with_cuts.stats["solves"][-1]["fewest_cuts"] is True


def test_the_cuts_keep_the_optimum_with_an_object_in_the_hand(spec_example):
    """A held object may need only a place: N = 2 is then not excluded, so the cuts stay off at N = 3."""
    with_cuts = plan(spec_example, holding="bottle")
    without = plan(spec_example, holding="bottle", fewest_cuts=False)
    assert with_cuts.status == without.status == "optimal"
    assert with_cuts.objective == pytest.approx(without.objective, abs=1e-6)
    assert len(with_cuts.phases) == len(without.phases)
    assert validate_plan(spec_example, with_cuts, holding="bottle") == []


def test_a_longer_count_is_a_model_of_exactly_its_phases_cut_off_at_the_best_cost():
    """Beyond the fewest phases each count is solved on its own (last a place, none idle), asked to beat the best."""
    scenario = families.get_family("multi-2").sample(np.random.default_rng(900_009))  # 8 phases cost less than 7
    result = plan(scenario)
    assert result.status == "optimal" and len(result.phases) == result.stats["fewest_phases"] + 1
    fewest, longer = result.stats["solves"][0], result.stats["solves"][-1]
    assert fewest["phases"] == result.stats["fewest_phases"] and "cutoff" not in fewest
    assert longer["phases"] == len(result.phases) and longer["fewest_cuts"] is True
    assert longer["cutoff"] == pytest.approx(result.stats["fewest_phases_objective"])
    assert result.objective < longer["cutoff"]


def test_windows_are_unions_and_the_last_action_is_at_the_end():
    """V-C: the pick is early (carried through the push) or late (after an empty-hand push), never between."""
    scenario = families.draw_paper_push(np.random.default_rng(2024), "A")
    problem = prepare(scenario, Lattice.over(scenario.area, 0.05))
    pairs = PairCosts(problem)
    n = skeleton(problem, pairs).phases
    loose = action_windows(problem, n, pairs)
    tight = action_windows(problem, n, pairs, last_at_end=True)
    assert tight.phases[("place", "bottle")] == {n - 1} < loose.phases[("place", "bottle")]
    picks = sorted(tight.phases[("pick", "bottle")])
    assert picks != list(range(picks[0], picks[-1] + 1))  # a gap: not the hull
    push = ("push", "block")
    before = tight.given[(("pick", "bottle"), push, True)]
    after = tight.given[(("pick", "bottle"), push, False)]
    assert before and after and not before & after
    result = plan(scenario)
    assert result.status == "optimal" and len(result.phases) == n
    assert result.phases[-1].action == "place"
