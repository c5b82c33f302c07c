"""A/B of the candidate mask in one process: FastPhases of two checkouts, state by state alternating.

    python -m benchmarks.studies.ppo_speed.mask_ab OLD_CHECKOUT NEW_CHECKOUT

Records 300 random masked steps from seed 0 of each family (the states the walk of
``python -m benchmarks phases`` meets, with this process's own code), then computes each
state's table with both checkouts' ``FastPhases`` (a new one per scenario, as the
wrapper makes it), the two taking turns state by state, 7 rounds; per state the least
time of the rounds (load noise out). Asserts the two tables are equal; prints the mean
and median milliseconds per state.
"""

from __future__ import annotations

import importlib.util
import sys
import time

import gymnasium as gym
import numpy as np


def _module(checkout: str, name: str) -> object:
    spec = importlib.util.spec_from_file_location(name, f"{checkout}/fetchcarry_env/candidate_mask.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def walk(family: str, steps: int = 300) -> tuple:
    """The layout, lattice and (scenario, state) of each step of a random masked walk."""
    import fetchcarry_env  # noqa: F401

    env = gym.make("FetchCarryPushPhases-v0", family=family)
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    masks, base, seq = env.get_wrapper_attr("action_masks"), env.unwrapped, []
    for _ in range(steps):
        seq.append((base.scenario, base.state))
        _o, _r, terminated, truncated, _i = env.step(int(rng.choice(np.flatnonzero(masks()))))
        if terminated or truncated:
            env.reset()
    return env.get_wrapper_attr("layout"), base.lattice, seq


def main(old_checkout: str, new_checkout: str) -> None:
    mods = _module(old_checkout, "mask_old"), _module(new_checkout, "mask_new")
    for family in ("basic", "push", "corridor", "multi-2"):
        layout, lattice, seq = walk(family)
        per = np.full((2, len(seq)), np.inf)
        for rep in range(7):
            phases = [None, None]
            for n, (scenario, state) in enumerate(seq):
                tables = []
                for k, mod in enumerate(mods):
                    start = time.perf_counter()
                    if phases[k] is None or phases[k].scenario is not scenario:
                        phases[k] = mod.FastPhases(layout, scenario, lattice)
                    tables.append(phases[k].table(state))
                    per[k, n] = min(per[k, n], time.perf_counter() - start)
                if rep == 0:
                    assert (tables[0].mask == tables[1].mask).all() and (tables[0].actions == tables[1].actions).all()
        mean, median = 1e3 * per.mean(axis=1), 1e3 * np.median(per, axis=1)
        print(f"{family:9s} mean ms old {mean[0]:.3f} new {mean[1]:.3f} ({mean[0] / mean[1]:.2f}x)  "
              f"median old {median[0]:.3f} new {median[1]:.3f} ({median[0] / median[1]:.2f}x)")  # fmt: skip


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
