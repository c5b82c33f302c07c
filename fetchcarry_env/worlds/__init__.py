"""Every scenario generator, one small module each; :mod:`fetchcarry_env.families` registers them by name.

``rooms`` (the training families: the paper's V-B, V-C and IV-F layouts and ``multi``,
jittered, and their mixtures), ``paper`` (the paper's Section V cases, fixed), ``turned``
(held-out layouts: a room or corridor turned a quarter turn), ``objects`` (k objects on
several tables), ``apartment`` (rooms joined by doors and corridors), ``unseen``
(topologies no training family draws), ``perturbed`` (the training scenarios with what a
real home changes, physics included: ``physics``) and ``ladder`` (objects-1..4). ``base``
holds what they share and ``pushable`` the test that every piece of clutter on a goal can
be pushed off it. They import nothing from the registry.
"""
