"""training: expert datasets, learned baselines, the benchmark harness and the command line.

``training.load_policy(path)`` loads any run folder (``bc``, ``dagger``, ``ppo``) as a
policy with stable-baselines3's ``predict`` protocol.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["load_policy"]


def load_policy(path: str | Path, env: Any = None) -> Any:
    """The policy of run folder ``path`` (any kind); ``ValueError`` if it is not one."""
    from training.baselines.runs import load_policy as load

    return load(path, env)
