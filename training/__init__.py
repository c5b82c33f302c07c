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
    """The policy of run folder ``path`` (any kind); a ``ValueError`` (``RunFolderError``) if it is not one.

    ``env`` (a ``FetchCarryPushPhases-v0`` env, or a stable-baselines3 ``VecEnv`` of them)
    is where ``predict`` reads the action masks when it is given none: load the policy
    with the env it acts in, ``load_policy(run, env)``, to run it through
    stable-baselines3's ``evaluate_policy(policy, env)``, which passes no masks. A run
    folder is data, never code: ``config.json`` and the tensors are read within bounds
    and checked (:mod:`training.learners.runs`); anything else is refused.
    """
    from training.learners.runs import load_policy as load  # torch: loaded only when a run is

    return load(path, env)
