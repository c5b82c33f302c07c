"""Where one ``plan()`` call spends its time: cProfile's top functions by cumulative time.

    python -m benchmarks.studies.profile_plan CASE SEED [TIME_LIMIT_S] [ROWS]

``CASE`` is one of :data:`benchmarks.speed.oracle.CASES` (``objects-10``, ``covered-4``, ...),
drawn from ``SEED`` as the oracle benchmark draws it; the call has a wall-clock safety
stop of ``TIME_LIMIT_S`` (default 40). Prints the plan's status, its CPU seconds and the
``ROWS`` (default 30) functions with the most cumulative time.
"""

from __future__ import annotations

import cProfile
import pstats
import sys
import time

from benchmarks.speed.oracle import CASES
from expert import plan


def profile(case: str, seed: int, time_limit: float, rows: int) -> None:
    problem = CASES[case](seed)
    profiler = cProfile.Profile()
    cpu = time.process_time()
    profiler.enable()
    result = plan(problem.scenario, time_limit=time_limit, lattice=problem.lattice, holding=problem.holding)
    profiler.disable()
    print(f"{case} seed {seed}: {result.status}, {time.process_time() - cpu:.1f} s of CPU")
    pstats.Stats(profiler).sort_stats("cumulative").print_stats(rows)


if __name__ == "__main__":
    args = sys.argv[1:]
    profile(args[0], int(args[1]), float(args[2]) if len(args) > 2 else 40.0, int(args[3]) if len(args) > 3 else 30)
