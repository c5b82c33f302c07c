"""The tables of ``docs/benchmarks/worlds.md`` from the raw results in this folder: ``python table.py [after]``.

Reads ``expert-<family>.json`` (``fetchcarry evaluate-expert --json``) and
``baselines.jsonl`` (``baselines.py``) and prints one markdown row per family. With
``after``: the figures after the expert's fallback plan, from the chunks
``after/expert-<family>-<start>.json`` (one ``evaluate-expert --start K --episodes N``
run each; episodes of a family in order from 0), summed per family.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
FAMILIES = (*(f"objects-{k}" for k in range(1, 9)), "apartment", "unseen-layouts", "perturbed")


def after() -> None:
    """The expert's rows after the fallback: every chunk of a family summed (episodes from 0, in order)."""
    print("| family | expert episodes | expert success | fails | planner failures | replans | steps | plan s/episode "
          "| max plan s | s/decision |")  # fmt: skip
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for family in FAMILIES:
        chunks = [json.loads(p.read_text())[0] for p in sorted((HERE / "after").glob(f"expert-{family}-[0-9]*.json"))
                  if p.stat().st_size]  # fmt: skip
        if not chunks:
            continue
        episodes = sum(c["episodes"] for c in chunks)
        successes = sum(c["successes"] for c in chunks)
        steps = sum(c["mean_steps"] * c["episodes"] for c in chunks)
        cells = [f"{episodes}", f"{successes / episodes:.1%}", f"{episodes - successes}",
                 f"{sum(c['planner_failures'] for c in chunks)}", f"{sum(c['replans'] for c in chunks)}",
                 f"{steps / episodes:.1f}", f"{sum(c['planning_s'] for c in chunks) / episodes:.3f}",
                 f"{max(c['max_planning_s'] for c in chunks):.2f}",
                 f"{sum(c['policy_s'] for c in chunks) / steps:.3f}"]  # fmt: skip
        print(f"| `{family}` | " + " | ".join(cells) + " |")


def main() -> None:
    baselines: dict[tuple[str, str], dict] = {}
    for line in (HERE / "baselines.jsonl").read_text().splitlines():
        row = json.loads(line)
        if "policy" in row:
            baselines[row["family"], row["policy"]] = row
    print("| family | expert episodes | expert success | fails | replans | steps | plan s/episode | max plan s "
          "| s/decision | greedy (48) | random-phases (48) |")  # fmt: skip
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for family in FAMILIES:
        path = HERE / f"expert-{family}.json"
        cells = ["not run"] + [""] * 7
        if path.is_file():
            r = json.loads(path.read_text())[0]
            decisions = r["mean_steps"] * r["episodes"]
            cells = [f"{r['episodes']}", f"{r['success_rate']:.1%}", f"{r['episodes'] - r['successes']}",
                     f"{r['replans']}", f"{r['mean_steps']:.1f}", f"{r['mean_planning_s']:.3f}",
                     f"{r['max_planning_s']:.2f}", f"{r['policy_s'] / decisions:.3f}"]  # fmt: skip
        greedy, random = (baselines.get((family, p)) for p in ("greedy", "random-phases"))
        shown = [f"{b['success']:.0%}" if b else "" for b in (greedy, random)]
        print(f"| `{family}` | " + " | ".join(cells + shown) + " |")


if __name__ == "__main__":
    after() if sys.argv[1:] == ["after"] else main()
