"""The table of ``docs/benchmarks/worlds.md`` from the raw results in this folder: ``python table.py``.

Reads ``expert-<family>.json`` (``fetchcarry evaluate-expert --json``) and
``baselines.jsonl`` (``baselines.py``) and prints one markdown row per family.
"""

from __future__ import annotations

import json
from pathlib import Path

HERE = Path(__file__).resolve().parent
FAMILIES = (*(f"objects-{k}" for k in range(1, 9)), "apartment", "unseen-layouts", "perturbed")


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
    main()
