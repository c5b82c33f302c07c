"""Area bounds (the paper's IV-F, Eq. 27): the base disc stays inside the area.

``-L^areax / 2 <= x_k^rob <= L^areax / 2`` for an area centred on the origin; here the
area is any rectangle and the bound is on the base centre, shrunk by the robot's radius,
rounded inwards to the lattice (and clipped to the lattice's own extent, which the env
may choose larger than the area). The bounds are the base variables' bounds
(:meth:`expert.milp.grid.Grid.var_bounds`), so this module only documents and checks
them. Corridors (IV-F) are the area minus obstacles: the scenario's obstacles, handled
by Eq. 18 like any other (:mod:`expert.milp.collision`).
"""

from __future__ import annotations

from expert.milp.grid import Grid


def area_is_empty(grid: Grid) -> bool:
    """True when no lattice point keeps the base disc inside the area (no plan can exist)."""
    return grid.domain.empty
