"""Write ``expected.json``: rliable's own figures on fixed score matrices, which ``test_aggregate.py`` compares with.

Run in an environment where ``rliable`` imports (rliable 1.2.0 with pandas below 3; the
project's own environment has pandas 3, under which rliable's ``arch`` does not import):

    python tests/training/rliable/make_expected.py

The matrices are (runs, tasks), drawn from a seeded generator; the figures are rliable's
IQM, mean, median, optimality gap, probability of improvement and performance profile,
and its stratified-bootstrap percentile intervals (50,000 repetitions).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import rliable
from rliable import library as rly
from rliable import metrics

REPS = 50_000
TAUS = [0.0, 0.25, 0.5, 0.75, 0.9, 1.0]


def matrices() -> dict[str, np.ndarray]:
    rng = np.random.default_rng(2021)
    base = rng.uniform(0.1, 0.9, size=7)
    return {
        "a": np.clip(base + rng.normal(0.05, 0.15, size=(3, 7)), 0, 1).round(4),
        "b": np.clip(base + rng.normal(0.0, 0.15, size=(5, 7)), 0, 1).round(4),
        "c": (rng.uniform(size=(3, 7)) > 0.5).astype(float),  # ties
    }


def main() -> None:
    scores = matrices()
    aggregate = lambda x: np.array([metrics.aggregate_iqm(x), metrics.aggregate_mean(x)])  # noqa: E731
    _, intervals = rly.get_interval_estimates(scores, aggregate, reps=REPS)
    pairs = {"a,b": (scores["a"], scores["b"]), "b,c": (scores["b"], scores["c"])}
    poi_points, poi_intervals = rly.get_interval_estimates(
        pairs, lambda x, y: np.array([metrics.probability_of_improvement(x, y)]), reps=REPS
    )
    profiles, _ = rly.create_performance_profile(scores, np.array(TAUS), reps=100)
    expected = {
        "rliable": rliable.__version__ if hasattr(rliable, "__version__") else "1.2.0",
        "reps": REPS,
        "taus": TAUS,
        "scores": {k: v.tolist() for k, v in scores.items()},
        "iqm": {k: float(metrics.aggregate_iqm(v)) for k, v in scores.items()},
        "median": {k: float(metrics.aggregate_median(v)) for k, v in scores.items()},
        "optimality_gap": {k: float(metrics.aggregate_optimality_gap(v)) for k, v in scores.items()},
        "iqm_interval": {k: intervals[k][:, 0].tolist() for k in scores},
        "mean_interval": {k: intervals[k][:, 1].tolist() for k in scores},
        "probability_of_improvement": {k: float(poi_points[k][0]) for k in pairs},
        "probability_of_improvement_interval": {k: poi_intervals[k][:, 0].tolist() for k in pairs},
        "profile": {k: np.asarray(v).tolist() for k, v in profiles.items()},
    }
    (Path(__file__).parent / "expected.json").write_text(json.dumps(expected, indent=1) + "\n")


if __name__ == "__main__":
    main()
