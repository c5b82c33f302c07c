"""The evaluation protocol's guard: training data never comes from a split's scenarios unless asked on purpose.

Seeds are guarded where data is made (:func:`training.data.generate.check_training_seeds`:
nothing from 10^9 up); this module adds the scenarios themselves: a fixed scenario
whose world (the scenario without its name) is one of a published split's (any part, any version that ships a reference
file) is refused with :class:`~training.data.generate.EvaluationSeedError` unless
``allow``. docs/protocol.md says what a paper reports.
"""

from __future__ import annotations

from functools import cache
from typing import Any

from fetchcarry_env.scenario import Scenario
from training.data.generate import EvaluationSeedError
from training.evaluation.references import part_references
from training.evaluation.results import scenario_digest
from training.evaluation.splits import published_splits


@cache
def split_digests() -> dict[str, str]:
    """Every published split scenario's world digest (its name left out) -> ``SPLIT episode K``."""
    return {
        r["world_digest"]: f"{split.name} episode {r['index']}"
        for split in published_splits()
        for r in part_references(split)
    }


def refuse_split_scenario(scenario: Scenario | dict[str, Any], allow: bool = False) -> None:
    """:class:`EvaluationSeedError` when ``scenario`` is one of a published split's (unless ``allow``)."""
    if allow:
        return
    scenario = Scenario.from_dict(scenario) if isinstance(scenario, dict) else scenario
    where = split_digests().get(scenario_digest(scenario, named=False))
    if where is not None:
        raise EvaluationSeedError(
            f"scenario {scenario.name!r} is {where}, an evaluation scenario: training data on it is refused "
            "(pass --allow-evaluation-seeds to use it on purpose)"
        )
