"""plan() keeps its promises on interrupts and time: Ctrl-C is never swallowed, the deadline holds.

SCIP catches SIGINT itself during a solve (its parameter ``misc/catchctrlc``) and just
stops with status ``userinterrupt``; ``plan()`` must turn that into
``KeyboardInterrupt`` and never return a plan from an interrupted solve.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
from planner_cases import largest_scenario, many_obstacles
from pyscipopt import SCIP_EVENTTYPE, Eventhdlr

import expert.planning.solving as solving
from expert.milp import deadline as deadline_module
from expert.planner import plan
from expert.validate import validate_plan
from fetchcarry_env.families import draw_paper_multi
from fetchcarry_env.scenario import check_rules

ROOT = Path(__file__).resolve().parents[2]


class _InterruptAtFirstLp(Eventhdlr):
    """Calls SCIP's own interrupt (what its SIGINT handler does) when the first LP is solved."""

    def eventinit(self):
        self.model.catchEvent(SCIP_EVENTTYPE.LPSOLVED, self)

    def eventexec(self, event):
        self.model.interruptSolve()


LP_SCENARIO_SEED = 2  # draw_paper_multi(default_rng(2), 4) solves LPs (seeds 0 and 1 are settled in presolve)


def test_scip_user_interrupt_raises_keyboard_interrupt(monkeypatch):
    built = solving.build

    def build_with_interrupt(*args, **kwargs):
        milp = built(*args, **kwargs)
        milp.model.includeEventhdlr(_InterruptAtFirstLp(), "interrupt", "interrupts the solve")
        return milp

    monkeypatch.setattr(solving, "build", build_with_interrupt)
    with pytest.raises(KeyboardInterrupt):
        plan(draw_paper_multi(np.random.default_rng(LP_SCENARIO_SEED), 4))


SIGINT_SCRIPT = textwrap.dedent(
    """
    import sys, time
    import numpy as np
    from pyscipopt import SCIP_EVENTTYPE, Eventhdlr
    import expert.planner as planner
    import expert.planning.solving as solving
    from fetchcarry_env.families import draw_paper_multi

    class Slow(Eventhdlr):
        def eventinit(self):
            self.model.catchEvent(SCIP_EVENTTYPE.LPSOLVED, self)
        def eventexec(self, event):
            print("IN_SOLVE", flush=True)  # the SIGINT arrives during this second, inside SCIP's solve
            time.sleep(1.0)

    built = solving.build
    def build(*args, **kwargs):
        milp = built(*args, **kwargs)
        milp.model.includeEventhdlr(Slow(), "slow", "slows the solve down")
        return milp

    solving.build = build
    result = planner.plan(draw_paper_multi(np.random.default_rng(2), 4), time_limit=60.0)  # LP_SCENARIO_SEED
    print("PLAN", result.status, flush=True)
    """
)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_sigint_during_a_solve_stops_the_call_without_a_plan():
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-c", SIGINT_SCRIPT], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )
    try:
        assert proc.stdout.readline().strip() == "IN_SOLVE"  # a state, not a time: the solve is under way
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=300)  # a safety stop against a hang, not a speed bound
    finally:
        proc.kill()
    assert "PLAN" not in out
    assert proc.returncode != 0 and "KeyboardInterrupt" in err


# ---------------------------------------------------------------------- the safety stop
class _ClockRunningOut:
    """A clock for :mod:`expert.milp.deadline` that passes every deadline after its ``reads``-th reading.

    It makes the safety stop come at a chosen point of the call (a count of clock readings,
    the same at any load), so the test checks what happens there; how long the call takes
    after its deadline is measured by ``python -m benchmarks planner``, not asserted here.
    """

    def __init__(self, reads: int) -> None:
        self.reads, self.read = reads, 0

    def perf_counter(self) -> float:
        self.read += 1
        return time.perf_counter() + (1e9 if self.read > self.reads else 0.0)


@pytest.mark.parametrize("reads", [1, 3, 30, 300, 3000])
@pytest.mark.parametrize("name", ["multi-10", "obstacles-400", "largest"])
def test_the_safety_stop_ends_the_call_wherever_it_comes_and_says_so(monkeypatch, name, reads):
    """Before: 10 objects took 9 s and 12 objects 53 s at a 0.5 s limit (the lower-bound search ran
    outside it), 1,000 obstacles raised RecursionError, the largest scenario spent 5 s preprocessing.

    Now every part checks the one deadline: wherever it passes (after 1 to 3,000 clock readings:
    preprocessing, the bounds, the first plans, building, solving), the call ends with what it has,
    says the clock stopped it, and makes no more than a few readings after that.
    """
    if name.startswith("multi"):
        scenario = draw_paper_multi(np.random.default_rng(0), int(name.split("-")[1]))
    elif name.startswith("obstacles"):
        scenario = many_obstacles(int(name.split("-")[1]))
    else:
        scenario = largest_scenario()
    assert check_rules(scenario) == []
    clock = _ClockRunningOut(reads)
    monkeypatch.setattr(deadline_module, "time", clock)
    result = plan(scenario, time_limit=3600.0)
    assert result.status in ("time_limit", "feasible", "optimal", "infeasible")
    if clock.read > reads:  # the deadline passed before the call ended
        assert result.stats["clock_stopped"] and result.stats["stopped_by"] == "clock"
        assert (result.status != "optimal" and "safety stop" in result.stats["optimality"]) or not result.found
        assert clock.read - reads <= 3, clock.read - reads
    if result.found:
        assert validate_plan(scenario, result) == []


def test_a_thousand_obstacles_plan_without_a_recursion_error():
    """The one-move connectivity walked the obstacles recursively (one frame each): RecursionError.

    plan() answers this layout from the reachability check before the bounds, so the least
    moves over all 1,000 obstacles are computed directly too (too many signatures for a table:
    a step counts one move, a lower bound).
    """
    from expert.milp.moves import problem_moves
    from expert.milp.problem import prepare
    from fetchcarry_env.actions import Lattice

    scenario = many_obstacles(1000)
    result = plan(scenario, time_limit=600.0)
    assert result.status in ("optimal", "feasible", "infeasible", "time_limit")
    assert "lower_bound" in result.stats or "cannot get to" in result.stats["reason"]
    problem = prepare(scenario, Lattice.over(scenario.area, 0.05))
    moves = problem_moves(problem)
    assert len(moves.rects) > 900 and moves.steps(problem, None, problem.grid.domain) >= 0
