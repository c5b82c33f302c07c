"""The planner's jobs, one module each: options, the run's record, solving one model, first plans, the deepening.

:func:`expert.planner.plan` is the public entry; ``docs/formulation.md`` says what each job
proves. Import direction: ``deepening`` -> ``first_plans`` -> ``solving`` -> ``run`` -> ``options``.
"""
