"""The ``--seed`` argument type: a whole number in ``[0, 2**32 - 1]``, the seeds numpy and Gymnasium take.

A seed outside that range used to end in a crash report (``rollout --seed -1``) or be
taken and fail later (``--seed 2**64``); argparse now refuses it with exit 2.
"""

from __future__ import annotations

import argparse

from fetchcarry_env.errors import InputError
from training.envs import MAX_SEED  # numpy's SeedSequence and Gymnasium's reset(seed=) take 0 .. 2**32 - 1


def seed(text: str) -> int:
    """A reset or training seed: a whole number from 0 to 2**32 - 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text[:40]!r}") from None
    if not 0 <= value <= MAX_SEED:
        raise argparse.ArgumentTypeError(f"a seed must be between 0 and 2**32 - 1 ({MAX_SEED}), got {text[:40]}")
    return value


def check_seed_range(first: int, count: int) -> None:
    """Raise :class:`InputError` unless seeds ``first .. first + count - 1`` are all valid seeds."""
    last = first + count - 1
    if last > MAX_SEED:
        raise InputError(
            f"the {count} episodes would use seeds {first} to {last}, beyond 2**32 - 1 ({MAX_SEED}): "
            "give a smaller --seed"
        )
