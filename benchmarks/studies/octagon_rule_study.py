"""What the env's octagon rules cost: the steps of episodes under the old rules that the new ones refuse.

Two checkouts: ``--old`` (the env's physical rules: a move stops at its first contact,
the exact arm line, 1 mm of reach) and ``--new`` (the planner's model). Run from
anywhere; each measurement runs in a child process with one checkout on its path.

``refusals``: masked-random episodes of ``FetchCarryPushPhases-v0`` and greedy episodes
of ``FetchCarryPush-v0`` under the old rules, each step asked, before it is taken, of
the new rules (the new checkout's ``rules.check_action``): how many steps the old env
accepted and the new one refuses, by the new rule's reason (move, acting pose, arm,
reach), and how many stopped at a contact under the old rules.

``expert``: the MILP expert's episodes (``ExpertPolicy``) in each checkout's env on the
same seeds: phases, travel, success and planning calls.

    python -m benchmarks.studies.octagon_rule_study --old OLD --new NEW [--episodes 20] [--expert-episodes 10]

prints one JSON object (the figures of docs/design.md, "The env's rules are the planner's model").
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import subprocess
import sys
from collections import Counter

FAMILIES = ("basic", "push", "corridor", "turned-corridor", "multi-2", "unseen-layouts", "apartment")
EXPERT_FAMILIES = ("basic", "push", "corridor", "multi-2", "objects-3")
MAX_STEPS = 50  # the registered episode length


def _new_rules(new: str):
    """The new checkout's ``rules`` module, loaded beside the old package, which keeps its own modules."""
    old = {name: sys.modules.get(f"fetchcarry_env.{name}") for name in ("regions", "rules")}
    for name in ("regions", "rules"):  # the new rules import the new regions by name: put them in place meanwhile
        spec = importlib.util.spec_from_file_location(f"fetchcarry_env.{name}", f"{new}/fetchcarry_env/{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[f"fetchcarry_env.{name}"] = module
        spec.loader.exec_module(module)
    for name, module_before in old.items():
        if module_before is None:
            sys.modules.pop(f"fetchcarry_env.{name}", None)
        else:
            sys.modules[f"fetchcarry_env.{name}"] = module_before
    return module


def _reason(text: str) -> str:
    """The rule a refusal of the new checkout names."""
    for key, rule in (("octagon", "move"), ("area", "move"), ("corner zone", "pose"), ("arm line", "arm")):
        if key in text:
            return rule
    return "reach" if "reach" in text else "other"


def refusals(old: str, new: str, episodes: int) -> dict:
    """In a process whose path starts with the old checkout: the old env's steps the new rules refuse."""
    sys.path.insert(0, old)
    import gymnasium as gym
    import numpy as np

    import fetchcarry_env.phase_env  # noqa: F401  (the old checkout's env, imported before the new rules load)
    from fetchcarry_env.actions import Action, Mode
    from fetchcarry_env.rules import check_action as old_check
    from training.policies.greedy import GreedyPolicy

    new_rules = _new_rules(new)
    out = {}
    for family in FAMILIES:
        for policy in ("random", "greedy"):
            env = gym.make("FetchCarryPushPhases-v0" if policy == "random" else "FetchCarryPush-v0", family=family)
            base = env.unwrapped
            greedy = GreedyPolicy(env) if policy == "greedy" else None
            tally: Counter = Counter()
            rng = np.random.default_rng(0)
            for seed in range(episodes):
                observation, _ = env.reset(seed=100_000 + seed)
                for _ in range(MAX_STEPS):
                    if greedy is None:
                        index = int(rng.choice(np.flatnonzero(env.get_wrapper_attr("action_masks")())))
                        vector, step = env.get_wrapper_attr("table").actions[index], index
                    else:
                        vector = step = greedy.predict(observation)[0]
                    action = Action.from_array(vector)
                    was = old_check(base.scenario, base.state, base.lattice, action)
                    now = new_rules.check_action(base.scenario, base.state, base.lattice, action)
                    observation, _r, terminated, truncated, info = env.step(step)
                    if isinstance(was, str):
                        continue
                    kind = "move" if action.mode == Mode.MOVE else "act"
                    tally[f"{kind} accepted"] += 1
                    tally["contacts"] += info["contact"] is not None
                    if isinstance(now, str):
                        tally[f"{kind} refused: {_reason(now)}"] += 1
                    if terminated or truncated:
                        break
            out[f"{family} {policy}"] = dict(sorted(tally.items()))
            env.close()
    return out


def expert(checkout: str, episodes: int, families: tuple[str, ...] = EXPERT_FAMILIES) -> dict:
    """In a process whose path starts with ``checkout``: the expert's episodes, per family and seed."""
    sys.path.insert(0, checkout)
    import gymnasium as gym

    import fetchcarry_env  # noqa: F401
    from expert import ExpertPolicy

    out = {}
    for family in families:
        env = gym.make("FetchCarryPush-v0", family=family)
        policy = ExpertPolicy(env)
        for seed in range(episodes):
            observation, info = env.reset(seed=100_000 + seed)
            policy.reset()
            phases = 0
            for phases in range(1, MAX_STEPS + 1):  # noqa: B007  (the count is the figure)
                observation, _r, terminated, truncated, info = env.step(policy.predict(observation)[0])
                if terminated or truncated:
                    break
            out[f"{family} {seed}"] = {
                "phases": phases + 1,
                "travel": round(info["travel_cost"], 6),
                "success": bool(info["is_success"]),
                "invalid": info["invalid_action"] is not None,
            }
        env.close()
    return out


def _child(mode: str, *args: str) -> dict:
    done = subprocess.run(
        [sys.executable, __file__, "--child", mode, *args], check=True, capture_output=True, text=True
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", help="checkout with the physical rules")
    parser.add_argument("--new", help="checkout with the octagon rules")
    parser.add_argument("--episodes", type=int, default=20, help="random and greedy episodes per family")
    parser.add_argument("--expert-episodes", type=int, default=10, help="expert episodes per family")
    parser.add_argument("--expert-families", default=",".join(EXPERT_FAMILIES), help="comma-separated families")
    parser.add_argument("--skip-refusals", action="store_true", help="measure the expert's episodes only")
    parser.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        mode, *rest = args.child
        if mode == "refusals":
            result = refusals(rest[0], rest[1], int(rest[2]))
        else:
            result = expert(rest[0], int(rest[1]), tuple(rest[2].split(",")))
        print(json.dumps(result))
        return
    if not (args.old and args.new):
        parser.error("--old and --new are both needed")
    report = {} if args.skip_refusals else {"refusals": _child("refusals", args.old, args.new, str(args.episodes))}
    old, new = (_child("expert", c, str(args.expert_episodes), args.expert_families) for c in (args.old, args.new))
    report["expert"] = {
        "episodes": len(old),
        "same phases": sum(old[k]["phases"] == new[k]["phases"] for k in old),
        "same travel": sum(abs(old[k]["travel"] - new[k]["travel"]) <= 1e-6 for k in old),
        "differ": {k: [old[k], new[k]] for k in old if old[k] != new[k]},
    }
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
