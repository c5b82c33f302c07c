"""Measurement, kept out of the three packages: speed benchmarks, studies and the tools they share.

Run from the repository's root (this folder is not installed with the package)::

    python -m benchmarks --help               # every benchmark and study that prints figures
    python -m benchmarks env                  # env steps per second, with the project's goals
    python -m benchmarks.studies.NAME ...     # a one-off study (its docstring says what it measured)

- :mod:`benchmarks.speed`: the speed benchmarks (env, planner, anytime, push, generate,
  phases, ppo; ``oracle`` for the planner at home scale) and their command options.
- :mod:`benchmarks.studies`: studies that back a figure of the docs (learning checks,
  the projection of the expert's moves, the ladder's run tools, A/B scripts).
- :mod:`benchmarks.same_records`: do two ``results.json`` hold the same records?

Their results are committed under ``docs/benchmarks/``, each with the command that made it.
"""
