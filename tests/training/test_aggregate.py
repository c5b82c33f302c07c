"""The figures across splits (IQM, performance profile, probability of improvement, stratified bootstrap) against
rliable 1.2.0's own numbers (``tests/training/rliable/expected.json``, made by ``make_expected.py`` there)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import trim_mean

from training.evaluation.aggregate import iqm, performance_profile, probability_of_improvement, stratified_bootstrap

EXPECTED = json.loads((Path(__file__).parent / "rliable" / "expected.json").read_text())
SCORES = {name: np.array(rows) for name, rows in EXPECTED["scores"].items()}
REPS = 20_000  # fewer than rliable's 50,000: intervals agree to bootstrap noise, not bit for bit


@pytest.mark.parametrize("name", sorted(SCORES))
def test_iqm_and_profile_are_rliables(name: str) -> None:
    assert iqm(SCORES[name]) == pytest.approx(EXPECTED["iqm"][name], abs=1e-12)
    np.testing.assert_allclose(performance_profile(SCORES[name], EXPECTED["taus"]), EXPECTED["profile"][name])


@pytest.mark.parametrize("pair", sorted(EXPECTED["probability_of_improvement"]))
def test_probability_of_improvement_and_its_interval_are_rliables(pair: str) -> None:
    x, y = (SCORES[name] for name in pair.split(","))
    assert probability_of_improvement(x, y) == pytest.approx(EXPECTED["probability_of_improvement"][pair], abs=1e-12)
    low, high = stratified_bootstrap(probability_of_improvement, (x, y), reps=REPS)
    expected_low, expected_high = EXPECTED["probability_of_improvement_interval"][pair]
    # "c" is all 0s and 1s, so the statistic takes few values and an end can sit between two of them: over four
    # random states rliable's own upper end on "b,c" is 0.810 or 0.857 (one step of 1/21)
    step = 0.05 if "c" in pair else 0.02
    assert low == pytest.approx(expected_low, abs=step) and high == pytest.approx(expected_high, abs=step)


@pytest.mark.parametrize("name", sorted(SCORES))
def test_stratified_bootstrap_intervals_of_iqm_and_mean_are_rliables(name: str) -> None:
    for figure, statistic in (("iqm_interval", iqm), ("mean_interval", lambda m: float(np.mean(m)))):
        low, high = stratified_bootstrap(statistic, (SCORES[name],), reps=REPS)
        expected_low, expected_high = EXPECTED[figure][name]
        assert low == pytest.approx(expected_low, abs=0.02) and high == pytest.approx(expected_high, abs=0.02)


def test_the_bootstrap_resamples_runs_within_each_task_and_repeats() -> None:
    one_run = np.array([[0.2, 0.4, 0.9]])
    assert stratified_bootstrap(iqm, (one_run,)) == (iqm(one_run), iqm(one_run))  # one run: no spread
    columns = np.array([[0.0, 1.0], [0.0, 1.0], [0.0, 1.0]])  # runs agree within a task, tasks differ
    assert stratified_bootstrap(lambda m: float(np.mean(m)), (columns,)) == (0.5, 0.5)  # tasks are never mixed
    spread = np.array([[0.1, 0.5], [0.9, 0.7], [0.4, 0.2]])
    assert stratified_bootstrap(iqm, (spread,)) == stratified_bootstrap(iqm, (spread,))
    assert iqm(spread) == pytest.approx(trim_mean(spread.ravel(), 0.25))
    with pytest.raises(ValueError, match="same tasks"):
        probability_of_improvement(spread, one_run[:, :2].T)
