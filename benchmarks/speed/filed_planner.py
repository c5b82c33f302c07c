"""A planning worker for another checkout of the project: times its ``expert.plan`` in its own process.

Run with that checkout first on the path (``PYTHONPATH=OTHER python benchmarks/speed/filed_planner.py``);
it imports only ``expert`` and ``fetchcarry_env``, so it runs against the planner as it
was at any earlier commit. One JSON request per line on stdin::

    {"scenario": <scenario dict>, "holding": null | "id", "lattice": [ox, oy, res, nx, ny] | null,
     "time_limit": seconds}

and one JSON answer per line on stdout: ``status``, ``phases``, ``objective`` (that
checkout's own objective), ``wall_s`` and ``cpu_s`` (the call, in-process). The benchmark
of :mod:`benchmarks.speed.oracle` drives it.
"""

from __future__ import annotations

import json
import sys
import time

from expert import plan  # the checkout first on PYTHONPATH
from fetchcarry_env.actions import Lattice
from fetchcarry_env.scenario import Scenario


def answer(request: dict) -> dict:
    """Plan one request with the checkout on the path; its status, size and seconds."""
    scenario = Scenario.from_dict(request["scenario"])
    lattice = None
    if request.get("lattice") is not None:
        ox, oy, resolution, nx, ny = request["lattice"]
        lattice = Lattice((ox, oy), resolution, (int(nx), int(ny)))
    wall, cpu = time.perf_counter(), time.process_time()
    result = plan(scenario, time_limit=request["time_limit"], lattice=lattice, holding=request.get("holding"))
    return {
        "status": result.status,
        "phases": len(result.phases),
        "objective": result.objective,
        "wall_s": time.perf_counter() - wall,
        "cpu_s": time.process_time() - cpu,
    }


def main() -> None:
    for line in sys.stdin:
        if line.strip():
            print(json.dumps(answer(json.loads(line))), flush=True)


if __name__ == "__main__":
    main()
