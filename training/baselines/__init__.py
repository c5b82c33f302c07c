"""Baselines on the candidate-phase interface: masked random and behaviour cloning (``predict`` protocol)."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def load_policy(path: str | Path, env: Any = None) -> Any:
    """The policy of a run folder (``config.json``'s ``kind``: bc, dagger or ppo); ``ValueError`` otherwise."""
    from training.baselines.runs import load_policy as load_run

    return load_run(path, env)
