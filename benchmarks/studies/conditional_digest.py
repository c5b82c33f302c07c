"""A digest of the planner's conditional bounds per case, to compare two checkouts.

Run it in each checkout with the same ``PYTHONHASHSEED`` (a state's frozensets print in
the order of their strings' hashes, which Python draws per process):

    PYTHONHASHSEED=0 PYTHONPATH=CHECKOUT python -m benchmarks.studies.conditional_digest CASE ...

A case is ``covered:K:SEED``, ``multi:K:SEED`` or ``FAMILY:SEED``, as in ``bounds_ab.py``.
Per case one line: a SHA-256 prefix over the skeleton graph (its states, edges, phases
and travel per edge) and the conditional bounds of every action, pose box and phase, for
the skeleton's N and N + 1 phases, each with and without the last place at N - 1. Equal
lines: the two checkouts compute the same graph and the same bounds. Also the seconds, at N, of
the first graph search (which fills the pair costs, as the planner's first model does)
and then of the whole conditional bound.
"""

from __future__ import annotations

import hashlib
import sys
import time

import gymnasium as gym
import numpy as np

import fetchcarry_env  # noqa: F401  (registers the env ids)
from expert.milp import bounds, conditional
from expert.milp.bounds import PairCosts, skeleton
from expert.milp.conditional import conditional_bounds
from expert.milp.deadline import NEVER
from expert.milp.problem import prepare
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_covered, draw_paper_multi

_SEARCHED_PER_CALL = hasattr(conditional, "_Graph")  # checkouts before e6bf9b1, where the skeleton graph became shared


def graph_of(problem, n_phases: int, pairs: PairCosts):
    """The skeleton graph the conditional bounds of ``n_phases`` search, in this checkout's code."""
    if _SEARCHED_PER_CALL:
        return conditional._Graph.search(problem, n_phases, pairs, NEVER)
    return pairs.graph().within(n_phases)


def scenario_of(case: str):
    """The scenario and lattice a case names (``bounds_ab.py`` reads its cases with it too)."""
    parts = case.split(":")
    if parts[0] in ("covered", "multi"):
        draw = draw_paper_covered if parts[0] == "covered" else draw_paper_multi
        scenario = draw(np.random.default_rng(int(parts[2])), int(parts[1]))
        return scenario, Lattice.over(scenario.area, 0.05)
    env = gym.make("FetchCarryPush-v0", family=parts[0])
    env.reset(seed=int(parts[1]))
    return env.unwrapped.scenario, env.unwrapped.lattice


def costs_of(problem):
    """The checkout's pair costs and, in checkouts that had it (before the exact least moves), its one-move
    connectivity (None after)."""
    connectivity = getattr(bounds, "Connectivity", None)
    if connectivity is None:
        return PairCosts(problem), None
    free = connectivity(problem)
    return PairCosts(problem, free), free


def digest(case: str) -> tuple[str, float, float]:
    """The case's digest, and the seconds of its first graph search and of its first conditional bounds."""
    problem = prepare(*scenario_of(case))
    pairs, free = costs_of(problem)
    n = skeleton(problem, free if _SEARCHED_PER_CALL else pairs).phases
    sha = hashlib.sha256()
    clock = time.perf_counter()
    graph_of(problem, n, pairs)
    search_s = time.perf_counter() - clock
    clock = time.perf_counter()
    conditional_bounds(problem, n, pairs, NEVER)
    conditional_s = time.perf_counter() - clock
    for phases in (n, n + 1):
        for last_at_end in (False, True):
            graph = graph_of(problem, phases, pairs)
            sha.update(repr(graph.states).encode())
            for array in (graph.src, graph.dst, graph.q, graph.t):
                sha.update(array.tobytes())
            bounds = conditional_bounds(problem, phases, pairs, NEVER, last_at_end).bound
            for slot in sorted(bounds, key=repr):
                sha.update(repr(slot).encode())
                sha.update(bounds[slot].tobytes())
    return sha.hexdigest()[:16], search_s, conditional_s


if __name__ == "__main__":
    for item in sys.argv[1:]:
        value, search_s, conditional_s = digest(item)
        print(f"{item} {value}  search {search_s:.2f} s, conditional bounds {conditional_s:.2f} s", flush=True)
