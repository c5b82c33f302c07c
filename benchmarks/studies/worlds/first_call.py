"""Where a first planning call's seconds go, and the fallback plan: ``python first_call.py FAMILY:SEED ...``.

For each episode (the scenario ``reset(seed=SEED)`` draws) one JSON line: the planner's
stats for one call with the expert's 10 s limit (``expert.planner.plan``: preprocessing,
reachability, lower bounds, decoupled plan, model building, solving; a stage cut off by
the deadline records no time, so ``lower_bound`` None means the bounds never finished),
then the expert's fallback plan (``expert.decoupled.fallback_plan``, 30 s budget): its
status, phases, seconds and which of its two tries gave it. Seconds are wall clock.
"""

from __future__ import annotations

import functools
import json
import sys
import time

import gymnasium as gym

import fetchcarry_env  # noqa: F401  (registers the env ids)
from expert import planner
from expert import policy as expert_policy
from expert.decoupled import fallback_plan
from expert.milp.deadline import Deadline

STAGES = ("prepare_s", "reach_s", "lower_bound_s", "decoupled_s", "build_s", "solve_s", "total_s")


def profile(family: str, seed: int, time_limit: float = 10.0, fallback_s: float = 30.0) -> dict:
    env = gym.make("FetchCarryPush-v0", family=family)
    env.reset(seed=seed)
    scenario, lattice = env.unwrapped.scenario, env.unwrapped.lattice
    result = planner.plan(scenario, time_limit=time_limit, lattice=lattice)
    stats = result.stats
    row = {"family": family, "seed": seed, "objects": len(scenario.objects), "status": result.status,
           **{k: round(stats.get(k, 0.0), 3) for k in STAGES}, "lower_bound": stats.get("lower_bound"),
           "phases_tried": stats.get("phases_tried"), "decoupled": stats.get("decoupled")}  # fmt: skip
    started = time.perf_counter()
    sub_plan = functools.partial(expert_policy._sub_plan, {})
    order = [o.id for o in scenario.objects]
    fallback = fallback_plan(scenario, order, lattice, Deadline.after(fallback_s), sub_plan)
    seconds = round(time.perf_counter() - started, 3)
    row.update(fallback_status=fallback.status, fallback_phases=len(fallback.phases), fallback_s=seconds,
               fallback_how=fallback.stats.get("decoupled"))  # fmt: skip
    env.close()
    return row


if __name__ == "__main__":
    for item in sys.argv[1:]:
        name, seed = item.rsplit(":", 1)
        print(json.dumps(profile(name, int(seed))), flush=True)
