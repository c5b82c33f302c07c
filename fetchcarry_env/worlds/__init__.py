"""The graded worlds: scenario generators beyond the paper's layouts (one small module each).

``objects`` (k objects on several tables), ``apartment`` (rooms joined by doors and
corridors), ``unseen`` (topologies no training family draws) and ``perturbed`` (the
training scenarios with what a real home changes, physics included: ``physics``).
:mod:`fetchcarry_env.families` registers them; they import nothing from it.
"""
