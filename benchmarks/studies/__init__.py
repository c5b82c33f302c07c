"""Studies behind figures of the docs: ``python -m benchmarks learned|learning-checks|projection``, and scripts.

Each script here is run from the repository's root as ``python -m benchmarks.studies.NAME``
(its docstring gives the command that made the committed results).
"""
