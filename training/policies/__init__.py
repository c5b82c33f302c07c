"""Policies that need no training: the ``Policy`` protocol, masked random, greedy, and the expert in phases.

- :mod:`~training.policies.protocol`: :class:`Policy` (stable-baselines3's ``predict``)
  and the two helpers the episode loop uses;
- :mod:`~training.policies.random`: the masked random policy of each interface;
- :mod:`~training.policies.greedy`: decoupled task-then-motion planning;
- :mod:`~training.policies.phase_expert`: the MILP expert answering with candidate phases;
- :mod:`~training.policies.user`: a user's ``module:factory`` policy, checked.

Learned policies live in :mod:`training.learners`; :mod:`training.resolve` turns any
policy's name into one.
"""

from training.policies.protocol import Policy
from training.policies.random import RandomMaskedPolicy, RandomPhasePolicy

__all__ = ["Policy", "RandomMaskedPolicy", "RandomPhasePolicy"]
