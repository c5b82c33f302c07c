"""The public planner: :func:`plan` solves the paper's MILP on SCIP by iterative deepening.

``plan(scenario)`` preprocesses the scenario on the action lattice once
(:func:`expert.milp.problem.prepare`), then builds and solves the MILP with ``N``
phases for ``N`` = a proven lower bound (:mod:`expert.milp.bounds`), ``N + 1``, ...
until a plan is found, ``max_phases`` is passed, or time runs out (the paper's V-A:
"starting with N_pha = 3 and increasing this value by 1"). The first ``N`` with a plan
is the answer: ``optimal`` when SCIP proved it optimal for that ``N``.

Units are metres and seconds.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
import time
from pathlib import Path
from typing import Any

import pyscipopt

from expert.decoupled import decoupled_plan, steps_of
from expert.guide import guide_steps
from expert.milp.bounds import (
    Connectivity,
    PairCosts,
    Windows,
    action_windows,
    cheapest_schedule,
    counting_bound,
    min_objective,
    min_travel,
    skeleton,
)
from expert.milp.build import SolverSettings, build
from expert.milp.collision import Infeasible
from expert.milp.conditional import Conditional, add_conditional_cuts, conditional_bounds, fix_above, fix_unreached
from expert.milp.deadline import Deadline, TimeUp
from expert.milp.decode import SolvedPhase, phases_of, plan_objective, read_steps
from expert.milp.export import export_model
from expert.milp.grid import MAX_CORNER_DETAIL
from expert.milp.order import add_pick_order
from expert.milp.problem import Problem, prepare
from expert.milp.reach import unreachable_reason
from expert.milp.variables import Milp
from expert.milp.warm import add_branching_hint, add_warm_start
from expert.plans import Plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.scenario import Scenario

DEFAULT_RESOLUTION = 0.05  # metres: the env's default lattice
EXTRA_PHASES = 8  # phases tried beyond the lower bound when max_phases is not given
RESERVE_S = 0.01  # seconds kept back from each solve for decoding and bookkeeping
DECOUPLED_FROM = 4  # objects (3 with pushes): from this many the decoupled plan comes first (costs 5-10 %)
DECOUPLED_SHARE = 0.7  # of the time left, at most, for the decoupled plan
FIRST_PLAN_BELOW_S = 2.0  # seconds: with a longer limit the schedule's decoupled plan comes in time: no first plan
FIRST_PLAN_ALL_S = 1.0  # seconds: with less time left, the first decoupled plan may use all of it (nothing else would)
SECOND_PASS_FIRST_SOLUTIONS = False  # the passes of several objects at a time with SCIP's first solutions
ORDER_FIXINGS = True  # the ordered plan's model: options no plan in its order does fixed to 0 (fix_outside_order)
ORDERED_FIRST_PLAN = True  # the first plan is the MILP's in the relaxation's order of deliveries (ordered_plan)
ORDERED_SHARE = 0.3  # of the time left, at most, for the first plan in the relaxation's order (ordered_plan)
LOOKAHEADS = (1, 2, 3)  # objects planned together per step of the decoupled passes, one pass each (decoupled_plans)
LOOKAHEAD_MIN_S = 0.5  # seconds left in that share before a pass with more objects at a time is tried
_PLANNER_OPTIONS = {
    "integral",
    "lower_bound",
    "fewest_cuts",
    "conditional",
    "corner_detail",
    "guide_branching",
    "first_move_tangents",
    "corner_poses",
    "pose_tangents",
}


def optimality(extra_phases: int, status: str = "optimal", fewest_proven: bool = False) -> str:
    """What a plan of ``status`` made with ``extra_phases`` is proven to be (the sentence in ``stats["optimality"]``).

    Only what holds: the claim of optimality for ``optimal``; for ``feasible`` that it is not
    proven (and, with ``fewest_proven``, that the plan with the fewest phases was proven
    optimal among those); for a status without a plan, that there is no claim.
    """
    if extra_phases == 0:
        claim = "optimal for Eq. 1 among the plans with the fewest phases that admit one (the paper's deepening)"
    else:
        claim = (
            f"optimal for Eq. 1 among all plans of at most N + {extra_phases} phases (N: the fewest that admit a "
            "plan), each counted over N + extra_phases phases with idle phases at its end"
        )
    if status == "optimal":
        return claim
    if status == "feasible":
        fewest = (
            "; the plan with the fewest phases (stats['fewest_phases_objective']) was proven optimal among those"
            if fewest_proven
            else ""
        )
        return (
            "not proven optimal: the time ran out first (stats['gap'], when not None, is the proven gap); "
            f"the planner was looking for the plan {claim}{fewest}"
        )
    return f"no plan (status {status}), so no claim of optimality"


def plan(
    scenario: Scenario,
    *,
    time_limit: float = 10.0,
    max_phases: int | None = None,
    lattice: Lattice | None = None,
    holding: str | None = None,
    extra_phases: int = 0,
    export_models: str | os.PathLike | None = None,
    guide: Plan | None = None,
    **solver_options: Any,
) -> Plan:
    """Plan ``scenario`` (optimal for the fewest phases that admit a plan); never raises for "no plan".

    Args:
        scenario: the problem; its robot starts at ``robot.start`` with ``robot.heading``.
        time_limit: wall-clock seconds for the whole call: preprocessing, the lower
            bounds, model building and every solve count against it.
        max_phases: the largest number of phases (the start included) to try;
            default: the lower bound plus ``EXTRA_PHASES``.
        lattice: the env's action lattice; default ``Lattice.over(scenario.area, 0.05)``.
        holding: id of an object already in the hand at the start.
        extra_phases: ``k >= 0``. With ``k > 0``, once the fewest phases ``N`` that admit a
            plan are known, the MILP is solved again with ``N + k`` phases, warm-started
            from the ``N``-phase plan; plans with fewer phases are in that model as plans
            followed by idle phases (no move, no action), which are dropped from the
            answer. ``optimal`` then means optimal among all plans of at most ``N + k``
            phases, compared by Eq. 1 over ``N + k`` phases (``stats["optimality"]``).
        export_models: an existing folder: every MILP solved is written there as MPS with
            a JSON of its variables' meanings and its optimum (:mod:`expert.milp.export`);
            ``stats["solves"][i]["exported"]`` names the file.
        guide: a plan for this scenario from elsewhere (a learned policy's rollout, an
            earlier answer): SCIP's warm start in every model whose phases it fits (checked
            feasible first, so the options it beats are fixed as for the decoupled plan)
            and, with the solver option ``guide_branching=True``, a branching hint (its
            option binaries branched on first). Only the search changes: the answer and
            its proof are the same with any guide or none.
            ``stats["guide"]`` says whether it mapped onto the lattice and the options.
        **solver_options: ``integral`` (bool, default True: integer lattice bases),
            ``lower_bound`` (bool, default True: start at the proven lower bound, not 3),
            ``fewest_cuts`` (bool, default True: the valid inequalities of a model whose
            ``N - 1`` is proven to admit no plan, :mod:`expert.milp.fewest`),
            ``conditional`` (bool, default True: Eq. 1's lower bound per action, pose box and
            phase as cuts, and the options that cannot beat the warm start fixed to 0,
            :mod:`expert.milp.conditional`),
            ``corner_detail`` (int 1-6, default 1: the octagon; higher adds tangents of the
            rounded corners to Eq. 18, :func:`expert.milp.grid.corner_directions`: closer to the
            exact swept-disc rule, slower; ``docs/formulation.md``, "Collision model"),
            ``first_move_tangents`` (bool, default False: the first move may also pass a
            corner along the start's own tangents, :func:`expert.milp.grid.start_tangents`;
            never worse, one phase fewer on some diagonal gaps, 1.0-1.3x time; off by default
            so that the expert's plans, and so the datasets and split references made with
            it, stay those of the model they were made with),
            ``corner_poses`` (bool, default False: poses in a table's or obstacle's corner
            zone, off its rounded corner, are offered) and ``pose_tangents`` (bool, default
            False: Eq. 18 also gets the corner tangents seen from every pose's lattice point,
            :func:`expert.milp.pose_tangents.pose_grid`): closer to the exact rule where a gap or a
            corridor is passed on the way to or from a pose, slower; off by default as above
            (``docs/formulation.md``, "Poses in corner zones, tangents from the poses"),
            ``guide_branching`` (bool, default False: see ``guide``),
            ``separating`` / ``presolving`` / ``heuristics`` (``default``, ``off``,
            ``fast``, ``aggressive``), ``params`` (a dict of SCIP parameters), ``seed``.

    From four objects (three with pushes) a decoupled plan (:mod:`expert.decoupled`) is
    made first when ``time_limit`` is under ``FIRST_PLAN_BELOW_S``, before the lower bounds
    (nearest object first, each sub-plan SCIP's first solution: tens of milliseconds),
    and after the bounds in the relaxation's order: the answer if time runs out before SCIP finds
    better (``stats["gap"]`` None: no bound covers it), and SCIP's first incumbent when it
    has no more phases than the model.

    Returns:
        a :class:`~expert.plans.Plan` with ``status`` ``optimal`` (SCIP proved it, gap 0,
        in the sense of ``stats["optimality"]``), ``feasible`` (time ran out with a plan;
        ``stats["gap"]`` is SCIP's proven relative gap ``|primal - dual| / min(|primal|,
        |dual|)`` and ``stats["dual_bound"]`` the proven bound on Eq. 1),
        ``infeasible`` (``stats["reason"]`` says why when known) or ``time_limit``.

    Raises:
        KeyboardInterrupt: on Ctrl-C, also when SCIP caught the signal during a solve
            (it does so itself and just stops); an interrupted call returns no plan.
    """
    deadline = Deadline.after(time_limit)
    started = time.perf_counter()
    options = _Options.parse(solver_options, extra_phases)
    lattice = lattice or Lattice.over(scenario.area, DEFAULT_RESOLUTION)
    run = _Run(scenario, started, deadline, options.settings, extra_phases, options.fewest_cuts, options.conditional)
    run.export_dir = None if export_models is None else Path(export_models)
    run.corner_detail = options.corner_detail
    run.first_move_tangents = options.first_move_tangents
    run.corner_poses, run.pose_tangents = options.corner_poses, options.pose_tangents
    run.guide_plan, run.guide_branching = guide, options.guide_branching
    try:
        return run.plan(lattice, holding, options.integral, options.lower_bound, max_phases)
    except TimeUp:
        return run.out_of_time()


@dataclasses.dataclass(frozen=True)
class _Options:
    """:func:`plan`'s own solver options and the :class:`SolverSettings` of the rest."""

    integral: bool
    lower_bound: bool
    fewest_cuts: bool
    conditional: bool
    settings: SolverSettings
    corner_detail: int = 1
    guide_branching: bool = False
    first_move_tangents: bool = False
    corner_poses: bool = False
    pose_tangents: bool = False

    @classmethod
    def parse(cls, solver_options: dict[str, Any], extra_phases: int) -> _Options:
        """Check ``solver_options`` and ``extra_phases`` (``TypeError``, ``ValueError``) and split the options."""
        unknown = set(solver_options) - _PLANNER_OPTIONS - set(SolverSettings.__dataclass_fields__)
        if unknown:
            raise TypeError(f"plan() got unknown solver option(s): {', '.join(sorted(unknown))}")
        if not isinstance(extra_phases, int) or extra_phases < 0:
            raise ValueError(f"extra_phases must be a whole number >= 0, got {extra_phases!r}")
        options = dict(solver_options)
        detail = options.pop("corner_detail", 1)
        guide_branching = bool(options.pop("guide_branching", False))
        tangents = bool(options.pop("first_move_tangents", False))
        corners = bool(options.pop("corner_poses", False)), bool(options.pop("pose_tangents", False))
        if not isinstance(detail, int) or isinstance(detail, bool) or not 1 <= detail <= MAX_CORNER_DETAIL:
            raise ValueError(f"corner_detail must be a whole number from 1 to {MAX_CORNER_DETAIL}, got {detail!r}")
        own = [bool(options.pop(name, True)) for name in ("integral", "lower_bound", "fewest_cuts", "conditional")]
        return cls(*own, SolverSettings(**options), detail, guide_branching, tangents, *corners)


@dataclasses.dataclass
class _Run:
    """One call of :func:`plan`: its clock, its stats and the best plan found so far."""

    scenario: Scenario
    started: float
    deadline: Deadline
    settings: SolverSettings
    extra_phases: int
    fewest_cuts: bool = True
    conditional: bool = True
    stats: dict[str, Any] = dataclasses.field(default_factory=dict)
    best: tuple[str, tuple] | None = None  # (status, phases) of the best plan found so far
    warm: list[SolvedPhase] | None = None  # the decoupled plan as MILP steps, for warm starts
    conditionals: dict[tuple[int, bool], Conditional] = dataclasses.field(default_factory=dict)
    first_order: tuple[list[str], Lattice] | None = None  # the order (and lattice) of the ordered plan to come
    export_dir: Path | None = None  # where every solved MILP is written (expert.milp.export)
    corner_detail: int = 1  # Eq. 18's corner tangents (expert.milp.grid.corner_directions)
    first_move_tangents: bool = False  # the start's tangents for the first move (expert.milp.grid.start_tangents)
    corner_poses: bool = False  # poses in corner zones (expert.milp.options.pose_options)
    pose_tangents: bool = False  # the corner tangents seen from the poses (expert.milp.pose_tangents.pose_grid)
    guide_plan: Plan | None = None  # plan()'s guide
    guides: list[list[SolvedPhase]] = dataclasses.field(default_factory=list)  # the guide as MILP steps, compact too
    guide_branching: bool = False  # the guide's option binaries branched on first

    def __post_init__(self) -> None:
        self.stats.update(
            solver=solver_name(),
            phases_tried=[],
            prepare_s=0.0,
            lower_bound_s=0.0,
            build_s=0.0,
            solve_s=0.0,
        )

    def finish(self, status: str, phases: tuple = ()) -> Plan:
        self.stats["total_s"] = time.perf_counter() - self.started
        fewest_proven = "fewest_phases_objective" in self.stats  # set only after an optimal N-phase solve
        self.stats["optimality"] = optimality(self.extra_phases, status, fewest_proven)
        objective = plan_objective(self.scenario, phases) if phases else None
        return Plan(self.scenario.name, status, objective, tuple(phases), self.stats)

    def out_of_time(self) -> Plan:
        """The answer when time ran out before a solve gave a plan: the best plan so far, or ``time_limit``.

        The decoupled plan's proven gap (``stats["gap"]``) is measured against Eq. 1's lower
        bound of the last model tried (:func:`expert.milp.bounds.min_objective`) when that
        model has the plan's phases and one phase fewer is proven to admit no plan (so the
        optimum has as many phases); otherwise it is None: no bound covers the plan.
        """
        self.stats["timed_out"] = True
        if self.best is not None:
            self.stats["gap"] = self.stats["dual_bound"] = None
            phases = self.best[1]
            last = self.stats.get("solves", [{}])[-1]
            bound = last.get("objective_bound")
            if bound is not None and last.get("fewest_cuts") and last["phases"] == len(phases):
                value = plan_objective(self.scenario, phases)
                self.stats["dual_bound"] = bound
                self.stats["gap"] = abs(value - bound) / max(min(abs(value), abs(bound)), 1e-9)
            return self.finish("feasible", phases)
        return self.finish("time_limit")

    def plan(
        self, lattice: Lattice, holding: str | None, integral: bool, use_bound: bool, max_phases: int | None
    ) -> Plan:
        stats, deadline = self.stats, self.deadline
        problem = prepare(
            self.scenario,
            lattice,
            holding=holding,
            integral=integral,
            deadline=deadline,
            corner_detail=self.corner_detail,
            first_move_tangents=self.first_move_tangents,
            corner_poses=self.corner_poses,
            pose_tangents=self.pose_tangents,
        )
        stats["prepare_s"] = time.perf_counter() - self.started
        stats["options"] = len(problem.options)
        deadline.check()
        if problem.infeasible is not None:
            stats["reason"] = problem.infeasible
            return self.finish("infeasible")
        if self.guide_plan is not None:
            self.guides = guide_steps(problem, self.guide_plan.phases)
            stats["guide"] = "mapped" if self.guides else "not mappable (ignored)"
            stats["guide_phases"] = [len(steps) + 1 for steps in self.guides]
        if not problem.deliver:
            stats["phases_tried"].append(1)
            return self.finish("optimal", phases_of(problem, []))
        reason = self.unreachable(problem)  # before any MILP: a few milliseconds at any size
        if reason is not None:
            stats["reason"] = reason
            return self.finish("infeasible")
        many = holding is None and len(problem.deliver) >= DECOUPLED_FROM - (1 if problem.pushes.pushable else 0)
        if many and deadline.left() < FIRST_PLAN_BELOW_S:
            self.first_plan(problem, lattice)
        problem, pairs, first, fewer_infeasible = self.lower_bound(problem, use_bound)
        if many:
            self.better_first_plan(problem, lattice, pairs, first, fewer_infeasible and self.fewest_cuts)
        last = max_phases if max_phases is not None else first + EXTRA_PHASES
        return self.deepen(problem, pairs, first, last, fewer_infeasible, max_phases)

    def lower_bound(self, problem: Problem, use_bound: bool) -> tuple[Problem, PairCosts | None, int, bool]:
        """The phases to start deepening at (at least 3); with ``use_bound`` the relaxation's bounds too.

        Returns the problem (with the relaxation's ``earliest`` and ``min_travel`` when
        ``use_bound``), the pair costs (None without ``use_bound``), the first phase count
        and whether one phase fewer is proven to admit no plan.
        """
        deadline = self.deadline
        t_bound = time.perf_counter()
        free = Connectivity(problem, deadline)
        pairs = PairCosts(problem, free, deadline) if use_bound else None
        if use_bound:
            relaxation = skeleton(problem, pairs, deadline)
            problem = dataclasses.replace(
                problem, earliest=relaxation.earliest, min_travel=min_travel(problem, pairs, deadline)
            )
            proven = max(counting_bound(problem), relaxation.phases)
        else:
            proven = counting_bound(problem)
        first = max(3, proven)
        self.stats["lower_bound"] = first
        self.stats["lower_bound_s"] += time.perf_counter() - t_bound
        return problem, pairs, first, first == proven  # N - 1 phases proven to admit no plan

    def deepen(
        self,
        problem: Problem,
        pairs: PairCosts | None,
        first: int,
        last: int,
        fewer_infeasible: bool,
        max_phases: int | None,
    ) -> Plan:
        """Solve with ``first``, ``first + 1``, ... ``last`` phases: the first plan found is the answer."""
        stats = self.stats
        for n_phases in range(first, last + 1):
            stats["phases_tried"].append(n_phases)
            outcome = self.solve(problem, n_phases, pairs, fewest=fewer_infeasible and self.fewest_cuts)
            if outcome == "infeasible":
                fewer_infeasible = True
                continue
            if outcome == "time_limit":
                return self.out_of_time()
            status, steps = outcome
            self.best = (status, phases_of(problem, steps))
            if self.extra_phases and status == "optimal":
                self.solve_longer(problem, pairs, n_phases, steps)
            return self.finish(*self.best)
        if not stats["phases_tried"]:
            stats["reason"] = f"max_phases={max_phases} is below the lower bound {first}"
        else:
            stats["reason"] = f"no plan with {first} to {last} phases (every model was infeasible)"
        return self.finish("infeasible")

    def unreachable(self, problem: Problem) -> str | None:
        """:func:`expert.milp.reach.unreachable_reason`, timed in ``stats["reach_s"]``."""
        t_reach = time.perf_counter()
        reason = unreachable_reason(problem, self.deadline)
        self.stats["reach_s"] = time.perf_counter() - t_reach
        return reason

    def solve_longer(self, problem: Problem, pairs: PairCosts | None, n_phases: int, steps: list[SolvedPhase]) -> None:
        """Solve again with ``extra_phases`` more phases, warm-started from the optimal ``steps``; keep the best."""
        self.stats["fewest_phases"] = n_phases
        self.stats["fewest_phases_objective"] = plan_objective(self.scenario, self.best[1])
        longer = self.solve(problem, n_phases + self.extra_phases, pairs, warm=steps)
        if isinstance(longer, tuple):
            self.best = (longer[0], phases_of(problem, _without_trailing_idle(longer[1])))
        else:
            self.best = ("feasible", self.best[1])

    def first_plan(self, problem: Problem, lattice: Lattice) -> None:
        """The decoupled plan (:mod:`expert.decoupled`), nearest object first, before any bound: the last resort.

        It needs no search for an order, so it comes within tens of milliseconds (one
        single-object MILP per object) and a time-limited call has a valid plan early.
        """
        t0 = time.perf_counter()
        order = list(problem.deliver)
        left = self.deadline.left()
        share = left if left < FIRST_PLAN_ALL_S else DECOUPLED_SHARE * left
        budget = Deadline(min(self.deadline.at, time.perf_counter() + share))
        try:
            found = decoupled_plan(self.scenario, order, lattice, budget, _first_solution_planner, nearest=True)
        except TimeUp:
            found = None
        self.stats["decoupled_s"] = time.perf_counter() - t0
        if found is not None:
            self._keep_decoupled(found, "nearest")

    def better_first_plan(
        self, problem: Problem, lattice: Lattice, pairs: PairCosts | None, n_phases: int, fewest: bool
    ) -> None:
        """A first plan in the order of the relaxation's cheapest schedule, to warm-start SCIP.

        With ``ORDERED_FIRST_PLAN`` the first model's own MILP in that order comes first
        (:meth:`ordered_plan`, inside the first solve, on the same model) and the decoupled
        plans only when it finds no plan of the model's phases; otherwise the decoupled plans
        now (:meth:`decoupled_plans`).

        ``fewest``: the model with ``n_phases`` will get the fewest-phases cuts; the
        conditional bounds that give the order are then the ones that model uses (computed once).
        """
        if pairs is not None and self.conditional:  # a bound of the first model: counted as bound time
            t_bound = time.perf_counter()
            self.conditional_bounds(problem, n_phases, pairs, fewest)
            self.stats["lower_bound_s"] += time.perf_counter() - t_bound
        order = list(problem.deliver)
        if pairs is not None:
            if self.conditional:
                picks = self.conditional_bounds(problem, n_phases, pairs, fewest).order("pick")
            else:
                _, schedule = cheapest_schedule(problem, n_phases, pairs, self.deadline)
                picks = [key[1] for key, _ in schedule if key[0] == "pick"]
            order = picks + [i for i in order if i not in picks]
            if ORDERED_FIRST_PLAN:
                self.first_order = (order, lattice)
                return
        self.decoupled_plans(problem, lattice, n_phases, order)

    def decoupled_plans(self, problem: Problem, lattice: Lattice, n_phases: int, order: list[str]) -> None:
        """The decoupled plan in ``order`` with optimal sub-plans, then two and three objects at a
        time (``LOOKAHEADS``: while the best has more than ``n_phases`` phases, the lower bound, or
        is still the first plan; never all the objects at once), in ``DECOUPLED_SHARE`` of the time
        left; the better plan is kept (fewer phases, then lower Eq. 1) and warm-starts SCIP.

        The first plan's Eq. 1 is often 5-10 % above the schedule's (first solutions, a
        greedy order), and SCIP's incumbent starts from the warm start: kept alone, it left
        5-object plans 9 % above the optimum at a 1 s limit, and a 4-object one 16 % above when
        the first plan had the lower bound's phases and the schedule's one phase more. Three at
        a time finds plans of the fewest phases that one and two at a time miss on covered
        four (``docs/benchmarks/planner.md``, "Three objects at a time").
        """
        t0 = time.perf_counter()
        budget = Deadline(min(self.deadline.at, time.perf_counter() + DECOUPLED_SHARE * self.deadline.left()))
        for lookahead in (n for n in LOOKAHEADS if n == 1 or n < len(order)):
            phases = self.best[1] if self.best is not None else None
            good = phases is not None and len(phases) <= n_phases and self.stats.get("decoupled") != "nearest"
            if lookahead > 1 and (good or budget.left() < LOOKAHEAD_MIN_S):
                break
            try:
                sub_planner = _first_solution_planner if lookahead > 1 and SECOND_PASS_FIRST_SOLUTIONS else plan
                found = decoupled_plan(self.scenario, order, lattice, budget, sub_planner, lookahead)
            except TimeUp:
                break
            if found is not None and (phases is None or _better(self.scenario, found, phases)):
                self._keep_decoupled(found, f"schedule, lookahead {lookahead}")
        self.stats["decoupled_s"] = self.stats.get("decoupled_s", 0.0) + time.perf_counter() - t0
        if self.best is not None:
            self.warm = steps_of(problem, self.best[1])

    def ordered_plan(
        self, milp: Milp, problem: Problem, order: list[str], lattice: Lattice, pairs: PairCosts, fewest: bool
    ) -> bool:
        """The best plan of the model that delivers the objects in ``order`` (the relaxation's), as the first plan.

        The model restricted to that order (:func:`expert.milp.order.add_pick_order`) is
        solved within ``ORDERED_SHARE`` of the time left, with the options no plan in that
        order does fixed to 0 (:meth:`fix_outside_order`); then the restriction and those
        fixings are removed (SCIP back to its problem stage): the model is built once.
        Where the relaxation's order is the optimum's, the plan is the optimum itself, and as
        warm start it lets SCIP fix every option whose conditional bound it beats before the search
        (``docs/benchmarks/planner.md``, "A first plan in the relaxation's order"). It is
        kept when better than the best plan so far; without a plan of the model's phases
        the decoupled plans follow (:meth:`decoupled_plans`). Recorded in
        ``stats["ordered"]`` and ``stats["ordered_s"]``.

        When the order's model is infeasible at its root, the whole model is solved at its
        root too (:meth:`root_proof`) before any decoupled plan; where that proves it
        infeasible, the decoupled plans aim at one phase more (a plan of the next model's
        phases needs no pass of more objects at a time) and True is returned: the model
        needs no further solve. Otherwise False.
        """
        model, t0 = milp.model, time.perf_counter()
        restriction = add_pick_order(milp, order)
        outside = self.fix_outside_order(milp, problem, order, pairs, fewest)
        left = self.deadline.left()
        if left - RESERVE_S <= 0:
            raise TimeUp
        status = _optimize(model, min(left - RESERVE_S, ORDERED_SHARE * left))
        steps = read_steps(problem, milp, model.getBestSol()) if model.getNSols() else None
        at_root = status == "infeasible" and model.getNNodes() <= 1
        self.stats["ordered"] = {
            "status": status,
            "nodes": model.getNNodes(),
            "order": list(order),
            "fixed": len(outside),
        }
        model.freeTransform()
        for constraint in restriction:
            model.delCons(constraint)
        for z in outside:
            model.chgVarUb(z, 1.0)
        self.stats["ordered_s"] = time.perf_counter() - t0
        proven_infeasible = False
        if at_root:
            steps = self.root_proof(milp, problem)
            proven_infeasible = steps == "infeasible"
            if proven_infeasible:
                steps = None
        fits = False
        if steps is not None:
            phases = phases_of(problem, steps)
            fits = len(phases) <= milp.n_phases
            if self.best is None or _better(self.scenario, phases, self.best[1]):
                self._keep_decoupled(phases, "pick order of the relaxation")
                self.warm = steps
        if not fits:
            aim = milp.n_phases + 1 if proven_infeasible else milp.n_phases
            self.decoupled_plans(problem, lattice, aim, order)
        return proven_infeasible

    def fix_outside_order(self, milp: Milp, problem: Problem, order: list[str], pairs: PairCosts, fewest: bool) -> list:
        """Fix to 0 the options that no plan in ``order`` does, by the conditional bounds of those plans
        (:func:`expert.milp.conditional.fix_unreached`); returns them, to be freed with the order's restriction.

        Only with ``ORDER_FIXINGS`` and the conditional bounds on; counted in ``stats["ordered"]["fixed"]``.
        """
        if not (ORDER_FIXINGS and self.conditional):
            return []
        in_order = conditional_bounds(problem, milp.n_phases, pairs, self.deadline, last_at_end=fewest, order=order)
        return fix_unreached(milp, in_order)

    def root_proof(self, milp: Milp, problem: Problem) -> str | list[SolvedPhase] | None:
        """The whole model solved at its root node only: ``"infeasible"``, the steps of a plan found, or None.

        A node limit, not a time limit, so the outcome is the same at any load. The model is
        back in its problem stage afterwards unless it was proven infeasible. Counted in
        ``stats["ordered_s"]``; SCIP's status and nodes in ``stats["ordered"]["root"]`` and ``["root_nodes"]``.
        """
        model, t0 = milp.model, time.perf_counter()
        left = self.deadline.left() - RESERVE_S
        if left <= 0:
            raise TimeUp
        model.setParam("limits/nodes", 1)
        try:
            status = _optimize(model, left)
        finally:
            model.setParam("limits/nodes", -1)
        self.stats["ordered"].update(root=status, root_nodes=model.getNNodes())
        infeasible = status in ("infeasible", "inforunbd")
        steps = read_steps(problem, milp, model.getBestSol()) if not infeasible and model.getNSols() else None
        if not infeasible:
            model.freeTransform()
        self.stats["ordered_s"] += time.perf_counter() - t0
        return "infeasible" if infeasible else steps

    def conditional_bounds(self, problem: Problem, n_phases: int, pairs: PairCosts, fewest: bool) -> Conditional:
        """:func:`expert.milp.conditional.conditional_bounds`, once per phase count and ``fewest``."""
        key = (n_phases, fewest)
        if key not in self.conditionals:
            self.conditionals[key] = conditional_bounds(problem, n_phases, pairs, self.deadline, last_at_end=fewest)
        return self.conditionals[key]

    def _keep_decoupled(self, phases: tuple, how: str) -> None:
        self.best = ("feasible", phases)
        self.stats["decoupled"] = how
        self.stats["decoupled_phases"] = len(phases)
        self.stats["decoupled_objective"] = plan_objective(self.scenario, phases)

    def solve(
        self,
        problem: Problem,
        n_phases: int,
        pairs: PairCosts | None,
        warm: list[SolvedPhase] | None = None,
        fewest: bool = False,
    ):
        """Build and solve with ``n_phases``: ``"infeasible"``, ``"time_limit"`` or ``(status, steps)``.

        ``fewest``: ``n_phases - 1`` phases are proven to admit no plan (adds :mod:`expert.milp.fewest`'s cuts).
        The first model built first makes the first plan in the relaxation's order
        (:meth:`ordered_plan`) when :meth:`better_first_plan` left one to make.
        """
        stats, deadline = self.stats, self.deadline
        record: dict[str, Any] = {"phases": n_phases, "fewest_cuts": fewest}
        stats.setdefault("solves", []).append(record)
        bound, windows, cond = self.model_bounds(problem, n_phases, pairs, fewest, record)
        t0 = time.perf_counter()
        try:
            milp = build(problem, n_phases, self.settings, bound, windows, deadline, fewest=fewest)
        except Infeasible:
            record.update(status="infeasible", build_s=time.perf_counter() - t0, solve_s=0.0, nodes=0)
            stats["build_s"] += record["build_s"]
            return "infeasible"
        t1 = time.perf_counter()
        record["build_s"] = t1 - t0
        stats["build_s"] += t1 - t0
        if cond is not None:
            record["conditional_fixed"] = add_conditional_cuts(milp, cond)
        if self.first_order is not None:  # the first model built
            order, lattice = self.first_order
            self.first_order = None
            if self.ordered_plan(milp, problem, order, lattice, pairs, fewest):  # proven infeasible at its root
                record.update(status="infeasible", solve_s=0.0, nodes=stats["ordered"]["root_nodes"], root_proof=True)
                return "infeasible"
            t1 = time.perf_counter()
        warms = [warm] if warm is not None else self.warm_starts(n_phases)
        self.add_warm_starts(milp, problem, n_phases, cond, warms, record)
        if self.guides and self.guide_branching:
            fitting = [steps for steps in self.guides if len(steps) <= n_phases - 1]
            record["guide_priorities"] = add_branching_hint(milp, (fitting or self.guides)[-1])
        remaining = deadline.left() - RESERVE_S
        if remaining <= 0:
            raise TimeUp
        model = milp.model
        status = _optimize(model, remaining)
        record.update(status=status, solve_s=time.perf_counter() - t1, nodes=model.getNNodes())
        stats["solve_s"] += record["solve_s"]
        if self.export_dir is not None:
            mps, _ = export_model(milp, self.export_dir, {**record, "solver": solver_name()})
            record["exported"] = mps.name
        if status in ("infeasible", "inforunbd"):
            return "infeasible"
        if model.getNSols() == 0:
            return "time_limit"
        return ("optimal" if status == "optimal" else "feasible"), self.read_solution(problem, milp)

    def model_bounds(
        self, problem: Problem, n_phases: int, pairs: PairCosts | None, fewest: bool, record: dict[str, Any]
    ) -> tuple[float | None, Windows | None, Conditional | None]:
        """Eq. 1's lower bound, the action windows and the conditional bounds of the model (None without ``pairs``)."""
        if pairs is None:
            return None, None, None
        deadline = self.deadline
        cond = None
        t_bound = time.perf_counter()
        if self.conditional:  # its least value is min_objective's
            cond = self.conditional_bounds(problem, n_phases, pairs, fewest)
            bound = cond.least if math.isfinite(cond.least) else -math.inf  # no path: no cut, as min_objective
        else:
            bound = min_objective(problem, n_phases, pairs, deadline, last_at_end=fewest)
        windows = action_windows(problem, n_phases, pairs, deadline, last_at_end=fewest)
        record["objective_bound"] = bound if math.isfinite(bound) else None
        self.stats["lower_bound_s"] += time.perf_counter() - t_bound
        return bound, windows, cond

    def warm_starts(self, n_phases: int) -> list[list[SolvedPhase]]:
        """The plans that fit a model of ``n_phases``: the guide (as it is, compact) and the decoupled plan."""
        known = [*self.guides, *([self.warm] if self.warm is not None else [])]
        return [steps for steps in known if len(steps) <= n_phases - 1]

    def add_warm_starts(
        self,
        milp: Milp,
        problem: Problem,
        n_phases: int,
        cond: Conditional | None,
        warms: list[list[SolvedPhase]],
        record: dict[str, Any],
    ) -> None:
        """The warm starts SCIP accepts (each checked) and the options the best of those with
        ``n_phases`` phases beats (its Eq. 1 is the MILP's)."""
        if not warms:
            return
        accepted = [steps for steps in warms if add_warm_start(milp, steps)]
        record["warm_start"] = bool(accepted)
        if self.guides:  # whether SCIP took the guide itself (as it is or compact) as a first solution
            record["guide_warm_start"] = any(steps is guide for steps in accepted for guide in self.guides)
        full = [phases_of(problem, steps) for steps in accepted]
        values = [plan_objective(self.scenario, known) for known in full if len(known) == n_phases]
        if cond is not None and values:
            record["conditional_fixed"] += fix_above(milp, cond, min(values))

    def read_solution(self, problem: Problem, milp: Milp) -> list[SolvedPhase]:
        """The best solution's steps; its objective, dual bound and gap go to the stats."""
        stats, model = self.stats, milp.model
        steps = read_steps(problem, milp, model.getBestSol())
        stats["milp_objective"] = model.getObjVal()
        dual = model.getDualbound()
        stats["dual_bound"] = dual if abs(dual) < model.infinity() else None
        gap = model.getGap()
        stats["gap"] = gap if stats["dual_bound"] is not None and abs(gap) < model.infinity() else None
        return steps


def _optimize(model: pyscipopt.Model, time_limit: float) -> str:
    """SCIP's solve within ``time_limit`` seconds; its status. Raises ``KeyboardInterrupt`` on Ctrl-C.

    SCIP catches SIGINT itself (``misc/catchctrlc``) and just stops (``userinterrupt``): the
    Ctrl-C is passed on, so an interrupted solve never gives a plan.
    """
    model.setParam("limits/time", time_limit)
    model.optimize()
    status = model.getStatus()
    if status == "userinterrupt":
        raise KeyboardInterrupt("planning interrupted during the SCIP solve")
    return status


def _better(scenario: Scenario, phases: tuple, than: tuple) -> bool:
    """Fewer phases, or as many and a lower Eq. 1."""
    if len(phases) != len(than):
        return len(phases) < len(than)
    return plan_objective(scenario, phases) < plan_objective(scenario, than) - 1e-9


def _first_solution_planner(scenario: Scenario, **kwargs: Any) -> Plan:
    """:func:`plan` stopping at SCIP's first solution at the fewest phases, fast presolving and heuristics."""
    return plan(scenario, presolving="fast", heuristics="fast", params={"limits/solutions": 1}, **kwargs)


def _without_trailing_idle(steps: list[SolvedPhase]) -> list[SolvedPhase]:
    """``steps`` without the idle phases at the end (no action, no move): the padding of a shorter plan."""
    out = list(steps)
    while len(out) > 1 and out[-1].option is None and out[-1].cell == out[-2].cell:
        out.pop()
    return out


@functools.cache
def solver_name() -> str:
    """``"SCIP <major>.<minor>.<tech>"`` of the SCIP inside pyscipopt."""
    model = pyscipopt.Model()
    return f"SCIP {model.getMajorVersion()}.{model.getMinorVersion()}.{model.getTechVersion()}"
