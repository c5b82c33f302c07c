"""Assemble the paper's MILP for a number of phases, and the solver settings.

:func:`build` creates a fresh SCIP model and adds the groups of equations in the
paper's order; each group lives in its own module and cites its equations:

==========================  =============================================
module                      equations
==========================  =============================================
:mod:`.motion`              Eq. 1-3 (objective, motion)
:mod:`.actions`             Eq. 4-7 (pick, place, carry, grasp)
:mod:`.objects`             Eq. 8-13 (objects and hand, delivery)
:mod:`.postures`            Eq. 14-17 (heading x posture at the actions)
:mod:`.collision`           Eq. 18-19 (base and arm collisions)
:mod:`.push`                IV-E, Eq. 20-26 (push-aside)
:mod:`.area`                IV-F, Eq. 27 (area, corridors)
==========================  =============================================
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from pyscipopt import SCIP_PARAMSETTING, Model

from expert.milp.actions import add_action_constraints
from expert.milp.bounds import Windows
from expert.milp.collision import add_arm_constraints, add_collision_constraints
from expert.milp.deadline import NEVER, Deadline
from expert.milp.fewest import add_fewest_phase_cuts
from expert.milp.motion import add_motion_constraints, set_objective
from expert.milp.objects import add_delivery_constraints
from expert.milp.order import add_order_windows
from expert.milp.postures import add_posture_constraints
from expert.milp.problem import Problem
from expert.milp.push import add_push_constraints
from expert.milp.variables import Milp, create_variables

_SETTINGS = {
    "default": SCIP_PARAMSETTING.DEFAULT,
    "off": SCIP_PARAMSETTING.OFF,
    "fast": SCIP_PARAMSETTING.FAST,
    "aggressive": SCIP_PARAMSETTING.AGGRESSIVE,
}


DEFAULT_PARAMS: dict[str, Any] = {
    "presolving/maxrestarts": 0,  # restarts re-presolve tiny models for nothing (measured: 5 runs on a V-B model)
    "branching/relpscost/maxlookahead": 2,  # strong branching was 60-80 % of the time on 3-4 objects
}


@dataclass(frozen=True)
class SolverSettings:
    """How SCIP is run. The defaults are the measured fastest that still prove optimality.

    ``separating``/``presolving``/``heuristics``: ``default``, ``off``, ``fast`` or
    ``aggressive`` (SCIP's parameter settings); ``params``: any further SCIP parameters
    by name (``{"limits/gap": 0.01}``); ``seed``: SCIP's random seed shift.
    """

    separating: str = "off"
    presolving: str = "default"
    heuristics: str = "off"
    params: dict[str, Any] = field(default_factory=dict)
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("separating", "presolving", "heuristics"):
            if getattr(self, name) not in _SETTINGS:
                raise ValueError(f"solver option {name}={getattr(self, name)!r}: use one of {', '.join(_SETTINGS)}")

    def apply(self, model: Model) -> None:
        model.hideOutput()
        model.setSeparating(_SETTINGS[self.separating])
        if self.presolving != "default":
            model.setPresolve(_SETTINGS[self.presolving])
        if self.heuristics != "default":
            model.setHeuristics(_SETTINGS[self.heuristics])
        model.setParam("randomization/randomseedshift", self.seed)
        for name, value in {**DEFAULT_PARAMS, **self.params}.items():
            model.setParam(name, value)


def build(
    problem: Problem,
    n_phases: int,
    settings: SolverSettings | None = None,
    objective_bound: float | None = None,
    windows: Windows | None = None,
    deadline: Deadline = NEVER,
    fewest: bool = False,
) -> Milp:
    """The MILP of ``problem`` with ``n_phases`` phases (phase 0, the start, included).

    ``objective_bound``: a proven lower bound on Eq. 1 with this many phases
    (:func:`expert.milp.bounds.min_objective`), added as a valid inequality.
    ``windows``: the phases at which each action can happen (:func:`expert.milp.bounds.action_windows`).
    ``fewest``: ``n_phases - 1`` phases are proven to admit no plan; adds the valid
    inequalities of :mod:`expert.milp.fewest`.
    ``deadline``: checked between groups and per rectangle of Eq. 18 (raises :class:`~expert.milp.deadline.TimeUp`).
    """
    model = Model(f"fetchcarry_{problem.scenario.name}_{n_phases}")
    (settings or SolverSettings()).apply(model)
    milp = create_variables(problem, n_phases, model, windows)
    for add in (add_motion_constraints, add_action_constraints, add_delivery_constraints, add_posture_constraints):
        deadline.check()
        add(milp)
    add_collision_constraints(milp, deadline)
    for add in (add_arm_constraints, add_push_constraints):
        deadline.check()
        add(milp)
    if windows is not None:
        add_order_windows(milp, windows, deadline)
    if fewest:
        add_fewest_phase_cuts(milp)
    set_objective(milp, objective_bound)
    return milp
