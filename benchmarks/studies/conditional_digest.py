"""A digest of the planner's conditional bounds per case, to compare two checkouts.

Run this file with each checkout's code on the path (a state's sets are sorted before
they are printed, so any ``PYTHONHASHSEED`` gives the same line):

    PYTHONPATH=CHECKOUT python benchmarks/studies/conditional_digest.py CASE ...

A case is ``covered:K:SEED``, ``multi:K:SEED`` or ``FAMILY:SEED``, as in ``bounds_ab.py``.
Per case one line: a SHA-256 prefix over the skeleton graph (its states, edges, phases
and travel per edge) and the conditional bounds of every action, pose box and phase, for
the skeleton's N and N + 1 phases, each with and without the last place at N - 1. Equal
lines: the two checkouts compute the same graph and the same bounds. Also the CPU
seconds of the skeleton's search with the graph at N (which fill the pair costs and build
the graph, as the planner's first model does), and then of one conditional bound at N.
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
    clock = time.process_time()
    n = skeleton(problem, free if _SEARCHED_PER_CALL else pairs).phases
    graph_of(problem, n, pairs)  # the shared graph is built by the skeleton's search; before it, here
    search_s = time.process_time() - clock
    sha = hashlib.sha256()
    clock = time.process_time()
    conditional_bounds(problem, n, pairs, NEVER)
    conditional_s = time.process_time() - clock
    for phases in (n, n + 1):
        for last_at_end in (False, True):
            graph = graph_of(problem, phases, pairs)
            states = [(sorted(d), h, sorted(p), key, box) for d, h, p, key, box in graph.states]  # sets in one order
            sha.update(repr(states).encode())
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
