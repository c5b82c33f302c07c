"""Before and after in one run: the phases/plain speed and MaskablePPO's steps per second of two checkouts.

    python -m benchmarks.studies.ppo_speed.before_after OLD_CHECKOUT NEW_CHECKOUT > before-after.json

Each figure runs in a fresh process of the checkout's own code (``PYTHONPATH`` set to it),
the two checkouts taking turns figure by figure, so that both meet the same load:
``benchmarks.speed.phases.speed`` and ``time_split`` (300 random masked steps from seed 0,
the four families of ``python -m benchmarks phases``), then ``benchmarks.speed.ppo.ppo_speed``
(MaskablePPO on ``basic``, 2,048 env steps, the published rollout, epochs and batch size)
with 1 and 2 envs. Prints one JSON object: every record with the one-minute load average
after it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

FAMILIES = ("basic", "push", "corridor", "multi-2")
PHASES = """
import json, os
from benchmarks.speed.phases import speed, time_split
print(json.dumps({{"speed": speed({family!r}, {steps}), "split": time_split({family!r}, {steps}),
                   "load": os.getloadavg()[0]}}))
"""
PPO = """
import json, os
from benchmarks.speed.ppo import ppo_speed, as_row
print(json.dumps({{**as_row(ppo_speed("basic", {envs}, {steps})), "load": os.getloadavg()[0]}}))
"""


def run(checkout: str, code: str) -> dict:
    """The JSON the snippet ``code`` prints, run with ``checkout``'s code."""
    env = {**os.environ, "PYTHONPATH": checkout}
    done = subprocess.run([sys.executable, "-c", code], cwd=checkout, env=env, capture_output=True, text=True,
                          check=True)  # fmt: skip
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(old: str, new: str, steps: int = 300, ppo_steps: int = 2048) -> dict:
    out: dict = {"load_start": os.getloadavg()[0], "phases": [], "ppo": []}
    for family in FAMILIES:
        for name, checkout in (("before", old), ("after", new)):
            record = run(checkout, PHASES.format(family=family, steps=steps))
            out["phases"].append({"family": family, "code": name, **record})
    for envs in (1, 2):
        for name, checkout in (("before", old), ("after", new)):
            out["ppo"].append({"code": name, **run(checkout, PPO.format(envs=envs, steps=ppo_steps))})
    return out


if __name__ == "__main__":
    print(json.dumps(main(sys.argv[1], sys.argv[2]), indent=2))
