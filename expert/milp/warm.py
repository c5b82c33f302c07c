"""Warm starts: a known plan handed to SCIP as a first solution (``createSol``, ``checkSol``, ``addSol``).

A plan found earlier (the fewest-phases plan when :func:`expert.planner.plan` solves
again with extra phases, or any plan of at most ``N`` phases) is written as values of
every variable of a model with ``N`` phases, padded with idle phases (no move, no
action) at its end. SCIP starts from it as its incumbent, so a time-limited solve
never returns worse than that plan, and its bound prunes the search from the start.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from expert.milp.decode import SolvedPhase
from expert.milp.grid import DiagonalPlane

if TYPE_CHECKING:
    from expert.milp.variables import Milp


def solution_values(milp: Milp, steps: list[SolvedPhase]) -> _Values | None:
    """Values of the model's variables for ``steps`` (padded with idle phases), or None if it does not fit."""
    n = milp.n_phases
    if len(steps) > n - 1 or not steps:
        return None
    steps = list(steps) + [SolvedPhase(steps[-1].cell, None)] * (n - 1 - len(steps))
    values = _Values()
    if not _set_moves(milp, steps, values):
        return None
    _set_states(milp, steps, values)
    if not _set_regions(milp, values):
        return None
    return values


def _set_moves(milp: Milp, steps: list[SolvedPhase], values: _Values) -> bool:
    """The base's lattice point, its move and the option chosen at every phase; False if one is not in the model."""
    index = {id(option): o for o, option in enumerate(milp.problem.options)}
    for k, step in enumerate(steps, start=1):
        i, j = step.cell
        values[milp.u[k]], values[milp.v[k]] = float(i), float(j)
        dx = abs(i - _value(values, milp.u[k - 1]))
        dy = abs(j - _value(values, milp.v[k - 1]))
        values[milp.mx[k]], values[milp.my[k]], values[milp.mxy[k]] = dx, dy, abs(dx - dy)
        chosen = None if step.option is None else index.get(id(step.option))
        if step.option is not None and (chosen is None or chosen not in milp.z[k]):
            return False
        for o, z in milp.z[k].items():
            values[z] = 1.0 if o == chosen else 0.0
    return True


def _set_states(milp: Milp, steps: list[SolvedPhase], values: _Values) -> None:
    """What is held, delivered and pushed (and in which direction) after every phase."""
    problem = milp.problem
    held = {i: (1.0 if i == problem.holding else 0.0) for i in problem.deliver}
    done = dict.fromkeys(problem.deliver, 0.0)
    pushed = dict.fromkeys(problem.pushes.pushable, 0.0)
    by_key: dict = {}
    for k, step in enumerate(steps, start=1):
        option = step.option
        if option is not None:
            if option.kind == "pick":
                held[option.target] = 1.0
            elif option.kind == "place":
                held[option.target], done[option.target] = 0.0, 1.0
            else:
                pushed[option.target] = 1.0
                by_key[option.push.key] = 1.0
        for i in problem.deliver:
            values[milp.gsp[i][k]], values[milp.delta[i][k]] = held[i], done[i]
        for c in problem.pushes.pushable:
            values[milp.pushed[c][k]] = pushed[c]
        for key, series in milp._pushed_dir.items():
            if not isinstance(series[k], float):
                values[series[k]] = by_key.get(key, 0.0)


def _set_regions(milp: Milp, values: _Values) -> bool:
    """The region binaries: the first region holding both ends of each move; False if none does."""
    for k, planes, binaries in milp.regions:
        ends = [(values[milp.u[k]], values[milp.v[k]])]
        if k > 1:
            ends.append((values[milp.u[k - 1]], values[milp.v[k - 1]]))
        holding = [n for n, plane in enumerate(planes) if all(_holds(plane, p) for p in ends)]
        if not holding:
            return False
        if binaries is not None:
            for n, r in enumerate(binaries):
                values[r] = 1.0 if n == holding[0] else 0.0
    return True


def add_warm_start(milp: Milp, steps: list[SolvedPhase]) -> bool:
    """Give SCIP the plan ``steps`` as a first solution; True only when it is feasible in this model.

    The solution is checked against every constraint, bound and integrality
    (``checkSol``) before it is added: ``addSol`` alone is no such check (in the problem
    stage SCIP returns True for an infeasible solution too), and :func:`expert.milp.
    conditional.fix_above` relies on the answer to fix options to 0. An infeasible
    solution is not added. A feasible one is True even when SCIP keeps it no more (it
    has it already: a solution of the same model solved before, which SCIP keeps through
    ``freeTransform``).
    """
    values = solution_values(milp, steps)
    if values is None:
        return False
    model = milp.model
    if len(values) < model.getNVars():  # a variable this module does not know: let SCIP not guess
        return False
    solution = model.createSol()
    for var, value in values.items():
        model.setSolVal(solution, var, value)
    if not model.checkSol(solution, printreason=False, completely=True):
        model.freeSol(solution)
        return False
    model.addSol(solution, free=True)
    return True


GUIDE_PRIORITY = 10  # SCIP branching priority of a guide's option binaries (the others have 0)


def add_branching_hint(milp: Milp, steps: list[SolvedPhase]) -> int:
    """Branch first on the option binaries that ``steps`` (a guide plan) uses, at their phases; returns how many.

    A priority orders the search only: SCIP still explores (or prunes by bound) every
    branch, so the optimum and its proof do not depend on the hint.
    """
    index = {id(option): o for o, option in enumerate(milp.problem.options)}
    count = 0
    for k, step in enumerate(steps, start=1):
        if step.option is None or k >= milp.n_phases:
            continue
        z = milp.z[k].get(index.get(id(step.option), -1))
        if z is not None:
            milp.model.chgVarBranchPriority(z, GUIDE_PRIORITY)
            count += 1
    return count


class _Values:
    """Variable -> value (pyscipopt variables are not hashable: keyed by their unique names)."""

    def __init__(self) -> None:
        self.items_by_name: dict[str, tuple] = {}

    def __setitem__(self, var, value: float) -> None:
        self.items_by_name[var.name] = (var, value)

    def __getitem__(self, var) -> float:
        return self.items_by_name[var.name][1]

    def __len__(self) -> int:
        return len(self.items_by_name)

    def items(self):
        return self.items_by_name.values()


def _value(values: _Values, coordinate) -> float:
    return coordinate if isinstance(coordinate, float) else values[coordinate]


def _holds(plane, point: tuple[float, float]) -> bool:
    if isinstance(plane, DiagonalPlane):
        return plane.holds_at(*point)
    return plane.holds(point[plane.axis])
