"""The collision model against the exact swept-disc rule: phases and Eq. 1 per choice of corner tangents.

Run from the project root (it prints one line per scenario and a summary per choice):

    PYTHONPATH=. python tests/expert/collision_study.py --out results.json

Each single-object scenario is solved by the exhaustive search of the exact rule
(``lattice_search.search``, on a 0.1 m lattice) and by the planner on the same lattice
with each choice of :data:`CHOICES`: the octagon (``corner_detail=1``, the default), the
48-gon (``corner_detail=4``, :func:`expert.milp.grid.corner_directions`), and the octagon
with the poses in corner zones and the tangents seen from the poses (``corner_poses``,
``pose_tangents``), also with the start's tangents (``first_move_tangents``). Scenarios:
3 x 3 m rooms with random walls (``test_lattice_search.random_room``), L-shaped corridors
and diagonal gaps between two walls' corners drawn on purpose (below), and with
``--families`` the single-object families and the audit's corridor.

``--bench SCALE`` plans the benchmark's own cases up to three objects with the choices
instead (no exact search: time and plan per choice); ``--summary FILE`` summarises such
rows per group. Units: metres and seconds.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import statistics
import time
from pathlib import Path

import numpy as np
from lattice_search import search
from test_lattice_search import RESOLUTION, random_room

from expert.planner import plan
from expert.validate import validate_plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import get_family
from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import DeliveryObject, Obstacle, Robot, Scenario, Table, check_rules
from training.speed.planner import UP_TO_THREE_OBJECTS

CHOICES = {  # name: plan()'s options
    "octagon": {"corner_detail": 1},
    "48-gon": {"corner_detail": 4},
    "poses": {"corner_poses": True, "pose_tangents": True},
    "poses+start": {"corner_poses": True, "pose_tangents": True, "first_move_tangents": True},
}
AUDIT = ("corridor", 504)  # the audit's corridor: the exact rule needs 4 phases, the octagon 6
ROOM = Rect(0.0, 0.0, 3.0, 3.0)


def corridor_room(rng: np.random.Generator, name: str) -> Scenario:
    """An L-shaped corridor (bottom, then right) 0.46-0.8 m wide round a block, to a table in the top strip."""
    while True:
        wb, wr = (float(v) for v in rng.uniform(0.46, 0.8, 2))
        top = float(rng.uniform(2.0, 2.2))
        tx = float(rng.uniform(0.7, 1.6))
        scenario = Scenario(
            name=name,
            area=ROOM,
            robot=Robot((float(rng.uniform(0.3, 1.0)), wb / 2)),
            tables=(Table("table", Rect(tx - 0.25, 2.45, tx + 0.25, 2.95)),),
            obstacles=(Obstacle("block", Rect(0.0, wb, 3.0 - wr, top)),),
            objects=(DeliveryObject("bottle", (tx - 0.15, 2.55), (tx + 0.15, 2.55)),),
        )
        if not check_rules(scenario):
            return scenario


def diagonal_room(rng: np.random.Generator, name: str) -> Scenario:
    """Walls top-left and bottom-right whose corners leave a diagonal gap of 0.45-0.65 m at 30-60 degrees."""
    while True:
        gap, angle = float(rng.uniform(0.45, 0.65)), math.radians(float(rng.uniform(30.0, 60.0)))
        xa, yb = (float(v) for v in rng.uniform(1.0, 1.4, 2))
        xb, ya = xa + gap * math.cos(angle), yb + gap * math.sin(angle)
        scenario = Scenario(
            name=name,
            area=ROOM,
            robot=Robot((float(rng.uniform(0.3, 0.8)), float(rng.uniform(0.3, 0.8)))),
            tables=(Table("table", Rect(2.2, 2.2, 2.7, 2.7)),),
            obstacles=(Obstacle("wall_a", Rect(0.0, ya, xa, 3.0)), Obstacle("wall_b", Rect(xb, 0.0, 3.0, yb))),
            objects=(DeliveryObject("bottle", (2.3, 2.45), (2.6, 2.45)),),
        )
        if not check_rules(scenario):
            return scenario


FAMILIES = ("basic", "corridor", "turned-room", "turned-corridor")  # the single-object families without pushes


def scenarios(count: int, per_family: int = 0) -> list[Scenario]:
    """``count`` of each kind, seeded by their index (rooms from seed 100 on: the test uses 0-20), and
    ``per_family`` of each of :data:`FAMILIES` (7 x 7 m rooms: about a minute of search each), seeds 0, 1, ...,
    and then the audit's corridor (:data:`AUDIT`)."""
    out = [
        dataclasses.replace(get_family(f).sample(np.random.default_rng(s)), name=f"{f}-{s}")
        for f in FAMILIES
        for s in range(per_family)
    ]
    if per_family:
        family, seed = AUDIT
        out.append(dataclasses.replace(get_family(family).sample(np.random.default_rng(seed)), name=f"{family}-{seed}"))
    out += [random_room(np.random.default_rng(100 + s), f"room-{100 + s}") for s in range(count)]
    out += [corridor_room(np.random.default_rng(s), f"corridor-{s}") for s in range(count)]
    out += [diagonal_room(np.random.default_rng(s), f"diagonal-{s}") for s in range(count)]
    return out


def run(scenario: Scenario, known: dict | None = None) -> dict:
    """The exact search and every choice of corner tangents on one scenario.

    ``known``: rows of an earlier run by scenario name; a scenario found there takes its
    exact result from it (the search is deterministic; ``search_s`` is then None).
    """
    lattice = Lattice.over(scenario.area, RESOLUTION)
    if known and scenario.name in known:
        row = {"scenario": scenario.name, "exact": known[scenario.name]["exact"], "search_s": None}
    else:
        t0 = time.perf_counter()
        exact = search(scenario, lattice, max_phases=8)
        row = {
            "scenario": scenario.name,
            "exact": [exact.phases, exact.objective],
            "search_s": time.perf_counter() - t0,
        }
    for name, options in CHOICES.items():
        result = plan(scenario, lattice=lattice, time_limit=60.0, **options)
        valid = not result.found or validate_plan(scenario, result) == []
        row[name] = {
            "status": result.status,
            "phases": len(result.phases) if result.found else None,
            "objective": result.objective,
            "total_s": result.stats["total_s"],
            "valid": valid,
        }
    return row


def summary(rows: list[dict], name: str) -> str:
    """Phases above the exact rule's, Eq. 1 excess at equal phases (absolute and relative), time."""
    more = [r for r in rows if r["exact"][0] is not None and (r[name]["phases"] or 99) > r["exact"][0]]
    false_infeasible = [r for r in rows if r["exact"][0] is not None and r[name]["phases"] is None]
    equal = [r for r in rows if r["exact"][0] is not None and r[name]["phases"] == r["exact"][0]]
    excess = [r[name]["objective"] - r["exact"][1] for r in equal]
    relative = [e / max(abs(r["exact"][1]), 1e-9) for e, r in zip(excess, equal, strict=True)]
    over = [e for e in relative if e > 0.01]
    times = [r[name]["total_s"] for r in rows]
    return (
        f"{name:<8} more phases {len(more)} (no plan {len(false_infeasible)}) of "
        f"{sum(r['exact'][0] is not None for r in rows)} feasible; equal phases {len(equal)}: "
        f"Eq. 1 excess max {max(excess, default=0):.3f} m, over 1 %: {len(over)}; "
        f"invalid {sum(not r[name]['valid'] for r in rows)}; time median {statistics.median(times):.3f} s, "
        f"max {max(times):.3f} s"
    )


def bench_rows(
    scale: float, time_limit: float = 10.0, groups: tuple[str, ...] = UP_TO_THREE_OBJECTS, choices: tuple[str, ...] = ()
) -> list[dict]:
    """The benchmark's own scenarios (``training.speed.planner.cases(scale)``, its seed) with every choice.

    Interleaved per scenario, so the load moves all choices alike; on the env's 0.05 m
    lattice (the plan() default). Times in seconds.
    """
    from training.speed.planner import choice_rows

    def show(row: dict) -> None:
        print(row["case"], "  ".join(f"{n}: {row[n]['phases']} {row[n]['total_s']:.3f}" for n in row if n in CHOICES))

    picked = {name: CHOICES[name] for name in choices or tuple(CHOICES)}
    return choice_rows(scale, picked, time_limit=time_limit, groups=groups, each=show)


def bench_summary(rows: list[dict]) -> list[str]:
    """Per group: median plan() time per choice (and its ratio to the octagon's), plans better and worse than the
    octagon's (fewer phases, or equal phases and Eq. 1 lower by over 1 mm), unproven (time limit) and invalid plans."""
    out = []
    for group in dict.fromkeys(r["group"] for r in rows):
        mine = [r for r in rows if r["group"] == group]
        base = statistics.median(r["octagon"]["total_s"] for r in mine)
        cells = []
        for name in (n for n in CHOICES if n in mine[0]):
            median = statistics.median(r[name]["total_s"] for r in mine)
            better = sum(_better(r[name], r["octagon"]) for r in mine)
            worse = sum(_better(r["octagon"], r[name]) for r in mine)
            unproven = sum(r[name]["status"] != "optimal" for r in mine)
            invalid = sum(not r[name]["valid"] for r in mine)
            cells.append(
                f"{name} {median:.3f} s ({median / base:.1f}x, max {max(r[name]['total_s'] for r in mine):.2f} s, "
                f"better {better}, worse {worse}, unproven {unproven}, invalid {invalid})"
            )
        out.append(f"{group} n={len(mine)}: " + "; ".join(cells))
    return out


def _better(a: dict, b: dict) -> bool:
    """Plan ``a`` beats ``b``: a plan where ``b`` has none, fewer phases, or equal phases and Eq. 1 lower by 1 mm."""
    if a["objective"] is None:
        return False
    if b["objective"] is None:
        return True
    return a["phases"] < b["phases"] or (a["phases"] == b["phases"] and a["objective"] < b["objective"] - 1e-3)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=10, help="scenarios of each kind")
    parser.add_argument("--families", type=int, default=0, help="scenarios of each single-object family")
    parser.add_argument(
        "--bench", type=float, help="instead: the benchmark's cases at this scale (0.25: its speed run)"
    )
    parser.add_argument("--out", help="write the rows as JSON here")
    parser.add_argument("--groups", nargs="*", help="with --bench: only these groups (default: all up to 3 objects)")
    parser.add_argument("--choices", nargs="*", choices=list(CHOICES), help="with --bench: only these")
    parser.add_argument("--time-limit", type=float, default=10.0, help="with --bench: seconds per plan() call")
    parser.add_argument("--exact-from", help="take the exact search's results from these rows where they have them")
    parser.add_argument("--summary", help="instead: summarise the --bench rows in this JSON file")
    args = parser.parse_args()
    if args.summary:
        print("\n".join(bench_summary(json.loads(Path(args.summary).read_text(encoding="utf-8")))))
        return
    if args.bench is not None:
        groups, choices = tuple(args.groups or UP_TO_THREE_OBJECTS), tuple(args.choices or CHOICES)
        rows = bench_rows(args.bench, args.time_limit, groups, choices)
        if args.out:
            Path(args.out).write_text(json.dumps(rows, indent=1), encoding="utf-8")
        return
    known = None
    if args.exact_from:
        known = {r["scenario"]: r for r in json.loads(Path(args.exact_from).read_text(encoding="utf-8"))}
    rows = []
    for scenario in scenarios(args.count, args.families):
        row = run(scenario, known)
        rows.append(row)
        cells = "  ".join(f"{n}: {row[n]['phases']} {row[n]['objective']}" for n in CHOICES)
        print(f"{row['scenario']:<14} exact {row['exact']}  {cells}", flush=True)
    for name in CHOICES:
        print(summary(rows, name))
    if args.out:
        Path(args.out).write_text(json.dumps(rows, indent=1), encoding="utf-8")


if __name__ == "__main__":
    main()
