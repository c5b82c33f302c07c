"""What the published table is made of: its splits, its references and its learned baselines with their run names.

The pipeline (:mod:`training.reproduce.pipeline`) trains and benchmarks what this module
names; the aggregation (:mod:`training.reproduce.aggregate`) reads it back by the same
names. Run folder ``DIR/runs/NAME-sSEED`` is baseline ``NAME``'s run for training seed
``SEED`` (:func:`run_name`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from training.reproduce.budgets import Budget

CURVE_SPLIT = "iid"  # where the demonstrations curve is measured
OBJECTS_SPLIT = "objects"  # the graded worlds objects-1 .. objects-8: success and cost ratio against k
REFERENCES = ("expert", "random", "random-phases", "greedy")
ENSEMBLE = "dagger-aimed-ensemble"  # the run combining every seed's dagger-aimed network


@dataclass(frozen=True)
class Baseline:
    """A learned baseline of the table: its label, and the run folders of each training seed."""

    label: str  # e.g. "bc-mlp"
    runs: tuple[str, ...]  # run folder names, one per training seed
    demonstrations: int | None = None  # expert episodes it was trained on (the demonstrations curve), if fixed
    per_seed: bool = True  # False: one run made of every seed's runs (an ensemble), not of one seed


def run_name(label: str, seed: int) -> str:
    """The run folder name of baseline ``label`` for training seed ``seed``."""
    return f"{label}-s{seed}"


def run_names(label: str, seeds: int) -> tuple[str, ...]:
    """The run folder names of baseline ``label`` for training seeds ``0 .. seeds - 1``."""
    return tuple(run_name(label, seed) for seed in range(seeds))


def curve_label(episodes: int) -> str:
    """The label of the demonstrations curve's BC (flat MLP) baseline trained on ``episodes`` expert episodes."""
    return f"bc-mlp-n{episodes}"


def on_curve_only(label: str) -> bool:
    """Whether baseline ``label`` is a demonstrations-curve point (``bc-mlp-nN``), not a row of the table."""
    return re.fullmatch(r"bc-mlp-n\d+", label) is not None


def has_ensemble(seeds: int, budget: Budget) -> bool:
    """Whether the table has ``dagger-aimed-ensemble``: with ``dagger-aimed`` runs of two seeds or more."""
    return bool(budget.aimed_iterations) and seeds > 1


def baselines(seeds: int, budget: Budget) -> list[Baseline]:
    """The learned baselines of the table (the curve's BC runs last)."""
    main = [
        Baseline("bc-mlp", run_names("bc-mlp", seeds), budget.demonstrations),
        Baseline("bc-set", run_names("bc-set", seeds), budget.demonstrations),
        Baseline("dagger", run_names("dagger", seeds)),
        *([Baseline("dagger-aimed", run_names("dagger-aimed", seeds))] if budget.aimed_iterations else []),
        *([Baseline(ENSEMBLE, (ENSEMBLE,), per_seed=False)] if has_ensemble(seeds, budget) else []),
        Baseline("ppo-scratch", run_names("ppo-scratch", seeds)),
        Baseline("ppo-bc", run_names("ppo-bc", seeds)),
    ]
    return main + [Baseline(curve_label(n), run_names(curve_label(n), seeds), n) for n in budget.curve]
