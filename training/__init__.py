"""training: datasets, learned baselines, the benchmark and the ``fetchcarry`` command line.

``training.load_policy(path)`` loads any run folder (``bc``, ``dagger``, ``ppo``,
``ensemble``) as a policy with stable-baselines3's ``predict`` protocol
(:class:`training.policies.Policy`). ``training.benchmark`` runs policies against the
MILP expert. ``docs/design.md`` says which module owns what.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from training import moved

if TYPE_CHECKING:
    from training.policies.protocol import Policy

__all__ = ["load_policy"]

moved.install()


def load_policy(path: str | Path, env: Any = None) -> Policy:
    """The policy of run folder ``path`` (any kind); a ``ValueError`` if it is not one."""
    from training.learners.runs import load_policy as load  # torch: loaded only when a run is

    return load(path, env)
