"""Every choice of the planner in one frozen record: :class:`PlannerOptions`.

``plan(scenario, options=PlannerOptions(...))`` or, for one or two fields,
``plan(scenario, node_limit=20_000)``. The same scenario and options give the same plan,
bit for bit, at any load: every pass is budgeted by counted work (SCIP's branch-and-bound
nodes), never by a share of the wall clock. ``plan()``'s ``time_limit`` is only a safety
stop; a plan it stopped says so (``stats["clock_stopped"]``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from expert.milp.build import SolverSettings
from expert.milp.skeleton_graph import MAX_EDGES


@dataclass(frozen=True)
class PlannerOptions:
    """How the planner models, bounds and searches (units: counts of SCIP nodes, objects, phases).

    The model:

    - ``integral``: integer lattice bases (default); False solves with continuous bases and
      snaps them (faster with several objects, at most a few decimetres longer paths).

    Bounds and cuts (each only speeds up the search: the optimum is the same without it):

    - ``lower_bound``: start the phase counts at the relaxation's proven bound, not 3;
    - ``fewest_cuts``: the valid inequalities of a model whose one phase fewer admits no plan;
    - ``conditional``: the task cost's lower bound per action, pose box and phase, as cuts and fixings;
    - ``skeleton_edges``: the budget of the relaxation's graph, in edges (about 32 bytes each,
      several times that while it is built); past it the graph is not built, the planner
      goes on as with ``lower_bound=False`` and ``stats["skeleton"]`` says so.

    First plans (SCIP's warm starts), from ``decoupled_from`` objects to deliver (one fewer with pushes):

    - ``ordered_first_plan``: the first model solved in the relaxation's order of deliveries,
      within ``ordered_nodes`` nodes, with the options no plan in that order does fixed to 0
      (``order_fixings``);
    - the decoupled plans (:mod:`expert.decoupled`), one pass per entry of ``lookaheads``
      (objects planned together per step), each sub-plan within ``sub_plan_nodes`` nodes;
    - ``longer_ordered_nodes``: each longer phase count's model restricted likewise to the
      relaxation's order at that count, within this many nodes, before the whole model;
    - ``nearest_first_plan``: also the decoupled plan nearest object first before any bound
      (a plan to answer with should the safety stop come during the bounds).

    Budgets: ``node_limit`` nodes per model solve (None: until SCIP proves the optimum, the
    safety stop aside). A plan whose solve ran out of nodes has status ``feasible``.

    SCIP: ``separating``, ``presolving``, ``heuristics`` (``default``, ``off``, ``fast``,
    ``aggressive``), ``params`` (SCIP parameters by name), ``seed`` (its random seed shift);
    ``guide_branching``: a guide plan's option binaries are branched on first.
    """

    integral: bool = True
    lower_bound: bool = True
    fewest_cuts: bool = True
    conditional: bool = True
    skeleton_edges: int = MAX_EDGES
    ordered_first_plan: bool = True
    order_fixings: bool = True
    nearest_first_plan: bool = False
    decoupled_from: int = 4
    lookaheads: tuple[int, ...] = (1, 2, 3)
    guide_branching: bool = False
    node_limit: int | None = None
    ordered_nodes: int = 5_000
    longer_ordered_nodes: int = 200
    sub_plan_nodes: int = 2_000
    separating: str = "off"
    presolving: str = "default"
    heuristics: str = "off"
    params: Mapping[str, Any] = field(default_factory=dict)
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("ordered_nodes", "longer_ordered_nodes", "sub_plan_nodes", "decoupled_from", "skeleton_edges"):
            _check_count(name, getattr(self, name))
        if self.node_limit is not None:
            _check_count("node_limit", self.node_limit)
        if not self.lookaheads or any(not isinstance(n, int) or n < 1 for n in self.lookaheads):
            raise ValueError(f"lookaheads must be whole numbers >= 1, got {self.lookaheads!r}")
        self.settings  # noqa: B018  (checks the SCIP settings' names)

    @property
    def settings(self) -> SolverSettings:
        """SCIP's settings for every model (:class:`~expert.milp.build.SolverSettings`)."""
        return SolverSettings(self.separating, self.presolving, self.heuristics, dict(self.params), self.seed)

    def with_fields(self, **fields: Any) -> PlannerOptions:
        """These options with ``fields`` changed; ``TypeError`` naming an unknown field."""
        unknown = set(fields) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise TypeError(f"plan() got unknown option(s): {', '.join(sorted(unknown))}")
        return dataclasses.replace(self, **fields)


def _check_count(name: str, value: Any) -> None:
    if not isinstance(value, int) or isinstance(value, bool) or value < 1:
        raise ValueError(f"{name} must be a whole number >= 1, got {value!r}")
