"""Baselines on the candidate-phase interface: masked random and behaviour cloning (``predict`` protocol)."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def load_policy(path: str | Path, env: Any = None) -> Any:
    """The policy of a run folder (``config.json``'s ``kind`` says which baseline); ``ValueError`` otherwise."""
    from training.baselines.bc import load_bc

    return load_bc(path, env)
