"""The goals table of issue 20, section 2, from ``plan_ab.py`` rows: per case kind and checkout.

    python -m benchmarks.studies.goals_table ROWS.jsonl [BASE_CODE]

Per kind (the case without its seed: ``covered:4``, ``objects-8``, ...) and checkout
(``code``): how many calls ended proven optimal, the median and 95th percentile of the
call's seconds (``np.percentile``; a call stopped at its limit counts with its limit),
and, against ``BASE_CODE`` (default: the first checkout of the file), the median of the
per-case ratios of seconds (base / this) and how many cases have the same status, phases
and Eq. 1 (to 1e-6).
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict

import numpy as np


def main(argv: list[str]) -> int:
    with open(argv[0], encoding="utf-8") as lines:
        rows = [json.loads(line) for line in lines if line.strip()]
    codes = list(dict.fromkeys(row["code"] for row in rows))
    base = argv[1] if len(argv) > 1 else codes[0]
    by_case = defaultdict(dict)
    for row in rows:
        by_case[row["case"]][row["code"]] = row
    kinds = list(dict.fromkeys(case.rsplit(":", 1)[0] for case in by_case))
    print("| case | checkout | proven optimal | median | p95 | ratio to " + base + " (median, min-max) | same answer |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for kind in kinds:
        cases = [c for c in by_case if c.rsplit(":", 1)[0] == kind and all(code in by_case[c] for code in codes)]
        for code in codes:
            mine = [by_case[c][code] for c in cases]
            times = np.array([r["total_s"] for r in mine])
            proven = sum(r["status"] == "optimal" for r in mine)
            ratios = np.array([by_case[c][base]["total_s"] / by_case[c][code]["total_s"] for c in cases])
            same = sum(_same(by_case[c][base], by_case[c][code]) for c in cases)
            print(
                f"| {kind} | {code} | {proven} of {len(mine)} | {np.median(times):.2f} s | "
                f"{np.percentile(times, 95):.2f} s | {np.median(ratios):.2f} ({ratios.min():.2f}-{ratios.max():.2f}) | "
                f"{same} of {len(mine)} |"
            )
    return 0


def _same(a: dict, b: dict) -> bool:
    """Same status and phases, and Eq. 1 within 1e-6 (or both without a plan)."""
    if (a["status"], a["phases"]) != (b["status"], b["phases"]):
        return False
    if a["objective"] is None or b["objective"] is None:
        return a["objective"] is b["objective"]
    return abs(a["objective"] - b["objective"]) <= 1e-6


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
