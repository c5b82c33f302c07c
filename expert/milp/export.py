"""Export of the MILP of one phase count: an MPS file and a JSON of what its variables mean.

For researchers of learned MILP solving (learned branching, node selection, warm
starts): every model the planner solves, written as it was handed to SCIP (cuts and
fixings included, all exact: the optimum is the model's own), with the optimum SCIP
proved. ``fetchcarry plan --export-model DIR`` writes ``<scenario>_N<phases>.mps`` and
``<scenario>_N<phases>.json`` for each phase count solved; HiGHS or any MPS reader
finds the same optimum (``tests/expert/test_export.py``).

The JSON (``fetchcarry-milp/1``): the scenario, the phase count, SCIP's status, the
optimum (the task cost of the best plan, the objective's constant included; None when none
was proven; a longer count's model is written without the cutoff it was solved with),
SCIP's dual bound and solve time, the lattice (origin and resolution, metres:
a base coordinate ``u`` is ``origin_x + resolution * u``) and ``variables``: per
variable name, its kind and meaning.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from expert.milp.variables import Milp

MODEL_FORMAT = "fetchcarry-milp/1"
_SAFE = re.compile(r"[^A-Za-z0-9_.-]+")


def export_paths(directory: Path, scenario: str, n_phases: int) -> tuple[Path, Path]:
    """The MPS and JSON paths of the model of ``scenario`` with ``n_phases`` phases in ``directory``."""
    stem = f"{_SAFE.sub('_', scenario) or 'scenario'}_N{n_phases}"
    return directory / f"{stem}.mps", directory / f"{stem}.json"


def export_model(milp: Milp, directory: Path, solve: dict[str, Any]) -> tuple[Path, Path]:
    """Write ``milp`` (solved or not) as MPS and its meanings and optimum as JSON; returns both paths.

    ``solve``: the planner's record of the solve (``status``, ``solve_s``, ``nodes``).
    """
    model = milp.model
    mps, meta = export_paths(directory, milp.problem.scenario.name, milp.n_phases)
    with _replacing(mps) as partial:
        model.writeProblem(str(partial), trans=False, verbose=False)
    status = model.getStatus()
    optimum = model.getObjVal() if status == "optimal" and model.getNSols() > 0 else None
    dual = model.getDualbound() if status in ("optimal", "timelimit", "gaplimit", "sollimit") else None
    lattice = milp.problem.grid.lattice
    record = {
        "format": MODEL_FORMAT,
        "scenario": milp.problem.scenario.name,
        "phases": milp.n_phases,
        "sense": "minimize",
        "objective": "the task cost: travel (metres) + W1 * (objects not at their goals after each phase k >= 1)",
        "status": status,
        "optimum": optimum,
        "dual_bound": dual if dual is not None and math.isfinite(dual) and abs(dual) < 1e19 else None,
        "solver": solve.get("solver"),
        "solve_s": solve.get("solve_s"),
        "nodes": solve.get("nodes"),
        "lattice": {"origin": list(lattice.origin), "resolution": lattice.resolution},
        "variables": variable_meanings(milp),
    }
    with _replacing(meta) as partial:
        partial.write_text(json.dumps(record, indent=1), encoding="utf-8")
    return mps, meta


@contextlib.contextmanager
def _replacing(path: Path) -> Iterator[Path]:
    """A new file beside ``path`` to write, which then replaces ``path``'s directory entry.

    Whatever stands at ``path`` (a FIFO that would block a writer, a symlink to a file
    elsewhere) is replaced, never opened or followed; the new file keeps ``path``'s suffix,
    from which SCIP picks the format. Nothing is left behind when writing fails.
    """
    handle, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    os.close(handle)
    partial = Path(name)
    try:
        yield partial
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)


def variable_meanings(milp: Milp) -> dict[str, dict[str, Any]]:
    """Per variable name: ``kind`` (``base_x``, ``option``, ...), ``phase`` and what it stands for."""
    out: dict[str, dict[str, Any]] = {}

    def put(var, kind: str, phase: int | None, meaning: str, **extra: Any) -> None:
        if not isinstance(var, float) and var is not None:
            out[var.name] = {"kind": kind, "phase": phase, "meaning": meaning, **extra}

    for k in range(1, milp.n_phases):
        put(milp.u[k], "base_x", k, "the base's x after phase k, in lattice indices")
        put(milp.v[k], "base_y", k, "the base's y after phase k, in lattice indices")
        put(milp.mx[k], "move_x", k, "|dx| of the move of phase k (Eq. 2), lattice indices")
        put(milp.my[k], "move_y", k, "|dy| of the move of phase k (Eq. 2), lattice indices")
        put(milp.mxy[k], "move_xy", k, "||dx| - |dy|| of the move of phase k (Eq. 3), lattice indices")
        for o, z in milp.z[k].items():
            option = milp.problem.options[o]
            box = option.box
            put(
                z,
                "option",
                k,
                f"phase k does option {o}: {option.kind} {option.target!r} heading {option.heading} "
                f"posture {option.posture!r} from a base in the box",
                action=option.kind,
                target=option.target,
                heading=option.heading,
                posture=option.posture,
                box=[box.i_lo, box.i_hi, box.j_lo, box.j_hi],
                push=None if option.push is None else list(option.push.cells),
            )
    for name, series, meaning in (
        ("held", milp.gsp, "object is in the hand after phase k (theta^gsp)"),
        ("delivered", milp.delta, "object stands at its goal after phase k (delta)"),
        ("pushed", milp.pushed, "clutter has been pushed by phase k"),
    ):
        for item, values in series.items():
            for k, var in enumerate(values):
                put(var, name, k, f"{item!r}: {meaning}", item=item)
    for (item, direction), values in milp._pushed_dir.items():
        for k, var in enumerate(values):
            put(var, "pushed_towards", k, f"{item!r} has been pushed towards {direction} by phase k", item=item)
    for k, planes, binaries in milp.regions:
        for n, r in enumerate(binaries or []):
            put(r, "region", k, f"both ends of move k lie in region {n} of this rectangle (Eq. 18): {planes[n]}")
    for var in milp.model.getVars():
        out.setdefault(var.name, {"kind": "auxiliary", "phase": None, "meaning": "a helper of a valid inequality"})
    return out
