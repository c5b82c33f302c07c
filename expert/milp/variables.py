"""The MILP's variables for a given number of phases, named after the paper's symbols.

Phases are numbered ``k = 0 .. N-1``; phase 0 is the start (the paper's ``k = 1``), so
``N`` is the paper's ``N_pha``. Base coordinates are in lattice-index units
(:mod:`expert.milp.grid`); phase 0's are constants (the exact start, off the lattice).

=====================  ======================================================  =========
paper                  here                                                    kind
=====================  ======================================================  =========
x_k^rob, y_k^rob       ``u[k]``, ``v[k]`` (index units)                        int/cont
m_k^x, m_k^y, m_k^xy   ``mx[k]``, ``my[k]``, ``mxy[k]`` (index units)          cont >= 0
theta_k^{h,alpha} *    ``z[k][o]``: pose option ``o`` chosen at phase ``k``    binary
theta_{i,k}^{pck|plc}
theta_{i,k}^{gsp}      ``gsp[i][k]``                                           cont [0,1]
delta_{i,k}            ``delta[i][k]``                                         cont [0,1]
(pushed by phase k)    ``pushed[c][k]``                                        cont [0,1]
=====================  ======================================================  =========

``gsp``, ``delta`` and ``pushed`` are continuous because equalities with binaries make
them integral (Eq. 4-6 and 12 below are written as equalities).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from pyscipopt import Model, quicksum

from expert.milp.problem import Problem

if TYPE_CHECKING:
    from expert.milp.bounds import Windows

Expr = Any  # a pyscipopt variable or linear expression


@dataclass
class Milp:
    """A SCIP model of the problem with ``n_phases`` phases and handles to its variables."""

    model: Model
    problem: Problem
    n_phases: int
    u: list = field(default_factory=list)
    v: list = field(default_factory=list)
    mx: list = field(default_factory=list)
    my: list = field(default_factory=list)
    mxy: list = field(default_factory=list)
    z: list[dict[int, Any]] = field(default_factory=list)  # per phase: option index -> binary
    gsp: dict[str, list] = field(default_factory=dict)
    delta: dict[str, list] = field(default_factory=dict)
    pushed: dict[str, list] = field(default_factory=dict)
    objective: Any = None  # Eq. 1 as a linear expression (set by motion.set_objective)
    regions: list = field(default_factory=list)  # Eq. 18: (move k, planes, binaries or None when hard)
    _pushed_dir: dict[tuple[str, str], list] = field(default_factory=dict)
    _arm: list[list] = field(default_factory=list)
    _push: list[list] = field(default_factory=list)
    _misses: dict = field(default_factory=dict)
    _forced: dict | None = None

    # ------------------------------------------------------------ selections
    def arm_options_at(self, k: int) -> list[tuple[int, Any]]:
        """``(option, z)`` for the picks and places that phase ``k`` may do."""
        return self._arm[k]

    def push_options_at(self, k: int) -> list[tuple[int, Any]]:
        """``(option, z)`` for the pushes that phase ``k`` may do."""
        return self._push[k]

    def misses(self, box, plane) -> bool:
        """True when no point of ``box`` lies in ``plane`` (cached: the same pairs recur every phase)."""
        key = (box, plane)
        hit = self._misses.get(key)
        if hit is None:
            hit = self._misses[key] = box.clip(plane).empty
        return hit

    def base_boxes(self, e: int) -> list | None:
        """Boxes one of which must hold base_e, when an action that must happen can only happen there; else None.

        An action (every pick, place and push is done exactly once) whose binaries all sit
        at one phase ``t`` fixes the acting base to its options' boxes: base_t for a pick or
        place, base_{t-1} (the stroke's start) and base_t (its end) for a push.
        """
        if self._forced is None:
            phases: dict[tuple[str, str], set[int]] = {}
            for k, chosen in enumerate(self.z):
                for o in chosen:
                    option = self.problem.options[o]
                    phases.setdefault((option.kind, option.target), set()).add(k)
            forced: dict[int, list] = {}
            for (kind, target), at in phases.items():
                if len(at) != 1:
                    continue
                (t,) = at
                options = [self.problem.options[o] for o in self.z[t]]
                mine = [o for o in options if (o.kind, o.target) == (kind, target)]
                if kind == "push":
                    forced.setdefault(t - 1, [o.box for o in mine])
                    forced.setdefault(t, [o.end_box for o in mine])
                else:
                    forced.setdefault(t, [o.box for o in mine])
            self._forced = forced
        return self._forced.get(e)

    def action_sum(self, kind: str, target: str, k: int) -> Expr | None:
        """``theta_{i,k}^{kind}``: the sum of the options of ``kind`` on ``target`` at phase ``k`` (None if none)."""
        terms = [
            z
            for o, z in self.z[k].items()
            if self.problem.options[o].kind == kind and self.problem.options[o].target == target
        ]
        return quicksum(terms) if terms else None

    def candidate_at(self, candidate: int, k: int) -> Expr | None:
        """Whether push candidate ``candidate`` (index in the push plan) is done at phase ``k``."""
        wanted = self.problem.pushes.candidates[candidate]
        terms = [z for o, z in self.z[k].items() if self.problem.options[o].push is wanted]
        return quicksum(terms) if terms else None

    def candidate_uses(self, candidate: int) -> Expr | None:
        terms = [t for k in range(1, self.n_phases) if (t := self.candidate_at(candidate, k)) is not None]
        return quicksum(terms) if terms else None

    def pushed_towards(self, clutter_id: str, direction: str) -> list:
        """Per phase, whether ``clutter_id`` has been pushed along ``direction`` by then (made on first use)."""
        key = (clutter_id, direction)
        if key not in self._pushed_dir:
            values: list = [0.0]
            for k in range(1, self.n_phases):
                terms = [
                    z for o, z in self.z[k].items() if (p := self.problem.options[o].push) is not None and p.key == key
                ]
                if not terms:
                    values.append(values[-1])
                    continue
                var = self.model.addVar(f"pushed_{clutter_id}_{direction}_{k}", lb=0.0, ub=1.0)
                self.model.addCons(var == values[-1] + quicksum(terms), name=f"pushed_{clutter_id}_{direction}_{k}")
                values.append(var)
            self._pushed_dir[key] = values
        return self._pushed_dir[key]


def create_variables(problem: Problem, n_phases: int, model: Model, windows: Windows | None = None) -> Milp:
    """Add every variable of the formulation with ``n_phases`` phases to ``model``.

    ``windows``: the phases at which each action can happen at all
    (:func:`expert.milp.bounds.action_windows`); no binary outside them.
    """
    milp = Milp(model, problem, n_phases)
    grid = problem.grid
    start = problem.scenario.robot.start
    vtype = "I" if grid.integral else "C"
    (u_lo, u_hi), (v_lo, v_hi) = grid.var_bounds(0), grid.var_bounds(1)
    if problem.start_index is not None:  # on a lattice point (up to float noise): use it exactly
        milp.u.append(float(problem.start_index[0]))
        milp.v.append(float(problem.start_index[1]))
    else:
        milp.u.append(grid.index_of(0, start[0]))
        milp.v.append(grid.index_of(1, start[1]))
    for series in (milp.mx, milp.my, milp.mxy):
        series.append(None)
    for k in range(1, n_phases):
        milp.u.append(model.addVar(f"x_rob_{k}", vtype=vtype, lb=u_lo, ub=u_hi))
        milp.v.append(model.addVar(f"y_rob_{k}", vtype=vtype, lb=v_lo, ub=v_hi))
        milp.mx.append(model.addVar(f"m_x_{k}", lb=0.0))
        milp.my.append(model.addVar(f"m_y_{k}", lb=0.0))
        milp.mxy.append(model.addVar(f"m_xy_{k}", lb=0.0))
    milp.z = [{} for _ in range(n_phases)]
    milp._arm = [[] for _ in range(n_phases)]
    milp._push = [[] for _ in range(n_phases)]
    for o, option in enumerate(problem.options):
        for k in option_phases(problem, option, n_phases):
            if windows is not None and not windows.allows((option.kind, option.target), k):
                continue
            z = milp.z[k][o] = model.addVar(f"z_{option.kind}_{option.target}_{o}_{k}", vtype="B")
            (milp._push if option.kind == "push" else milp._arm)[k].append((o, z))
    for object_id in problem.deliver:
        held = 1.0 if object_id == problem.holding else 0.0
        milp.gsp[object_id] = [held] + [
            model.addVar(f"gsp_{object_id}_{k}", lb=0.0, ub=1.0) for k in range(1, n_phases)
        ]
        milp.delta[object_id] = [0.0] + [
            model.addVar(f"delta_{object_id}_{k}", lb=0.0, ub=1.0) for k in range(1, n_phases)
        ]
    for clutter_id in problem.pushes.pushable:
        milp.pushed[clutter_id] = [0.0] + [
            model.addVar(f"pushed_{clutter_id}_{k}", lb=0.0, ub=1.0) for k in range(1, n_phases)
        ]
    return milp


def option_phases(problem: Problem, option, n_phases: int) -> range | list[int]:
    """The phases at which ``option`` can be chosen at all.

    A pick needs a later place (k <= N-2); a place of an object that is not held
    needs an earlier pick (k >= 2); a push needs a later place of the object it clears
    (k <= N-2; the hand may hold that object while pushing) and, as it starts from the
    previous phase's base, k >= 2 unless the start lies exactly on a lattice point of
    the option's box.
    """
    if option.kind == "pick":
        return range(1, n_phases - 1)
    if option.kind == "place":
        return range(1 if option.target == problem.holding else 2, n_phases)
    first = 1 if problem.start_index is not None and option.box.contains(*problem.start_index) else 2
    return range(first, n_phases - 1)
