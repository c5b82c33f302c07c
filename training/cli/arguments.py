"""Argument types for the command line: numbers checked by argparse, so bad values exit 2 with a message."""

from __future__ import annotations

import argparse
import math
from dataclasses import asdict

from fetchcarry_env.observation import Capacity, CapacityError


def whole_number(text: str) -> int:
    """An integer (seeds, episode indices)."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None


def capacity_text(text: str) -> str:
    """An observation capacity as ``KEY=N,...`` (checked here, passed on as text: it is JSON for a dataset's spec)."""
    try:
        capacity = Capacity.parse(text)
    except CapacityError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return ",".join(f"{k}={v}" for k, v in asdict(capacity).items())


def positive_int(text: str) -> int:
    """An integer of at least 1 (counts of episodes, workers, phases)."""
    value = whole_number(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {value}")
    return value


def non_negative_int(text: str) -> int:
    """An integer of at least 0 (extra phases)."""
    value = whole_number(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {value}")
    return value


def positive_float(text: str) -> float:
    """A finite number above 0 (seconds of a time limit)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"expected a positive finite number, got {text!r}")
    return value


def add_worker_options(parser: argparse.ArgumentParser) -> None:
    """``--workers``, ``--backend`` and ``--ray-address``: where episodes run (``generate``, ``benchmark``, ...)."""
    parser.add_argument("--workers", type=positive_int, default=1, metavar="W", help="parallel workers (default 1)")
    parser.add_argument(
        "--backend",
        choices=("process", "ray"),
        default="process",
        help="a local process pool (default) or Ray (optional extra: pip install ray)",
    )
    parser.add_argument("--ray-address", metavar="ADDR", help="a Ray cluster to join (default: start a local one)")
