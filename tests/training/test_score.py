"""The benchmark's score: 0 for doing nothing, 100 for the reference, no failure above a success on a scenario."""

from __future__ import annotations

import math

import pytest

from fetchcarry_env.registration import MAX_EPISODE_STEPS, do_nothing_return
from training.evaluation.metrics import score, scored_return


def episode(objects: int, success: bool, ret: float) -> dict:
    return {"objects": objects, "success": success, "return": ret}


def reference(ret: float, success: bool = True) -> dict:
    return {"success": success, "return": ret}


def test_doing_nothing_scores_0_and_the_reference_100() -> None:
    assert do_nothing_return(2) == -10.0 * 2 * MAX_EPISODE_STEPS == -1000.0
    scenarios = [(1, -40.0), (3, -180.0), (2, -95.5)]  # (objects, the reference's return)
    idle = [(episode(n, False, do_nothing_return(n)), reference(r)) for n, r in scenarios]
    assert score(idle) == pytest.approx(0.0)
    optimal = [(episode(n, True, r), reference(r)) for n, r in scenarios]
    assert score(optimal) == pytest.approx(100.0)


def test_no_failure_scores_above_a_success_on_the_same_scenario() -> None:
    floor = do_nothing_return(3)  # -1500
    lucky_failure = episode(3, False, -300.0)  # two objects delivered early, the third never: above the floor
    slow_success = episode(3, True, -1600.0)  # everything delivered in the last phases, far travelled: below it
    assert scored_return(lucky_failure) == floor == scored_return(slow_success)
    ref = reference(-200.0)
    assert score([(lucky_failure, ref)]) <= score([(slow_success, ref)]) == 0.0
    assert score([(episode(3, False, -2000.0), ref)]) < 0.0  # wandering without delivering: below doing nothing


def test_it_is_linear_in_the_returns_as_minaris_normalised_score() -> None:
    pairs = [(episode(1, True, -60.0), reference(-40.0)), (episode(2, True, -300.0), reference(-100.0))]
    floors = [do_nothing_return(1), do_nothing_return(2)]
    ref_min, ref_max = sum(floors) / 2, (-40.0 - 100.0) / 2
    mean_return = (-60.0 - 300.0) / 2
    assert score(pairs) == pytest.approx(100.0 * (mean_return - ref_min) / (ref_max - ref_min))


def test_scenarios_without_a_successful_reference_are_left_out() -> None:
    pairs = [(episode(1, True, -40.0), reference(-40.0)), (episode(1, True, -30.0), reference(-900.0, success=False))]
    assert score(pairs) == pytest.approx(100.0)
    assert math.isnan(score([(episode(1, True, -30.0), None)]))
