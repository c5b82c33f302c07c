"""The tables of ``docs/benchmarks/worlds.md`` from its raw results.

    python -m benchmarks.studies.worlds.table [after|seeds]


Reads ``expert-<family>.json`` (``fetchcarry evaluate-expert --json``) and
``baselines.jsonl`` (``baselines.py``) and prints one markdown row per family. With
``after``: the figures after the expert's fallback plan, from the chunks
``after/expert-<family>-<start>.json`` (one ``evaluate-expert --start K --episodes N``
run each; episodes of a family in order from 0), summed per family. With ``seeds``: the
expert on seeds 0-499 of each family, each episode counted once, from the chunks where they
start at 0 and otherwise from the first run (``expert-<family>.json``, seeds 0 .. N-1) and
the chunks from N on.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[3] / "docs" / "benchmarks" / "worlds"  # the raw results
FAMILIES = (*(f"objects-{k}" for k in range(1, 9)), "apartment", "unseen-layouts", "perturbed")


def after() -> None:
    """The expert's rows after the fallback: every chunk of a family summed, for the families run from seed 0.

    (``objects-3`` to ``objects-5`` have chunks only from the seed their first run stopped
    at: ``seeds`` counts them with it.)
    """
    print("| family | expert episodes | expert success | fails | planner failures | replans | steps | plan s/episode "
          "| max plan s | s/decision |")  # fmt: skip
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for family in FAMILIES:
        chunks = _chunks(family)
        if not chunks or chunks[0]["start"] > 0:
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


def _chunks(family: str) -> list[dict]:
    """The family's chunks after the fallback (``after/expert-<family>-<start>.json``), by start."""
    paths = sorted((HERE / "after").glob(f"expert-{family}-[0-9]*.json"))
    return [{**json.loads(p.read_text())[0], "start": int(p.stem.rsplit("-", 1)[1])} for p in paths if p.stat().st_size]


def seeds() -> None:
    """The expert on seeds 0 .. n-1 per family (n = 500 when complete): the first run's episodes, then the chunks'."""
    from training.stats import wilson

    print("| family | seeds | delivered every object | success | 95 % Wilson lower end | from | s/decision |")
    print("| --- | ---: | ---: | ---: | ---: | --- | ---: |")
    for family in FAMILIES:
        chunks = _chunks(family)
        first = HERE / f"expert-{family}.json"
        parts = []
        if (not chunks or chunks[0]["start"] > 0) and first.is_file():
            parts.append(("first run", {**json.loads(first.read_text())[0], "start": 0}))
        parts += [("after", c) for c in chunks]
        covered, kept = 0, []
        for name, part in sorted(parts, key=lambda p: p[1]["start"]):
            if part["start"] != covered:  # a gap or an overlap: count seeds 0 .. covered - 1 only, each once
                break
            covered += part["episodes"]
            kept.append((name, part))
        if not kept:
            continue
        episodes = sum(p["episodes"] for _, p in kept)
        successes = sum(p["successes"] for _, p in kept)
        decisions = sum(p["mean_steps"] * p["episodes"] for _, p in kept)
        sources = ", ".join(
            f"{n} {sum(p['episodes'] for m, p in kept if m == n)}" for n in dict.fromkeys(m for m, _ in kept)
        )
        cells = [f"{episodes}", f"{successes}", f"{successes / episodes:.1%}", f"{wilson(successes, episodes)[0]:.1%}",
                 sources, f"{sum(p['policy_s'] for _, p in kept) / decisions:.3f}"]  # fmt: skip
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
    {"after": after, "seeds": seeds}.get(sys.argv[1] if sys.argv[1:] else "", main)()
