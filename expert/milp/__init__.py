"""The paper's MILP (Section IV) on SCIP: preprocessing, one module per group of equations, decoding.

``problem.prepare`` -> ``build.build(problem, n_phases)`` -> SCIP -> ``decode``. The public
entry point is :func:`expert.planner.plan`; ``docs/formulation.md`` maps every equation
of the paper to the function that implements it.
"""
