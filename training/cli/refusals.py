"""``fetchcarry train KIND`` refuses to train on the benchmark's evaluation data unless asked on purpose.

Each learner's registry record names its refusal (:mod:`training.learners.refusals`);
``--allow-evaluation-seeds`` skips it, as it does for ``fetchcarry generate``.
"""

from __future__ import annotations

import argparse
from typing import Any

from training.learners import registry

FLAG_HELP = (
    "allow training on the benchmark's evaluation seeds (from 10^9) or a split's scenario: research on purpose "
    "(refused by default, exit 2, so that no one trains on what is reported)"
)


def add_refusal_option(parser: argparse.ArgumentParser) -> None:
    """``--allow-evaluation-seeds`` (not saved in the run folder's options: it changes no setting)."""
    parser.add_argument("--allow-evaluation-seeds", action="store_true", help=FLAG_HELP)


def refuse_evaluation_data(learner: registry.Learner, options: Any, allow: bool) -> None:
    """Raise :class:`~training.data.generate.EvaluationSeedError` if ``options`` would train on evaluation data."""
    if allow or learner.refuse is None:
        return
    registry.resolve(learner.refuse)(options)
