"""Do two ``results.json`` files hold the same records, timings aside?

    python benchmarks/same_records.py BEFORE/results.json AFTER/results.json [--policies expert greedy]

Either file may be the object of schema 1 (``{"schema_version": 1, "records": [...]}``)
or the earlier plain list. Records are matched by (policy, split, source, seed) and
compared field by field, every field but the timings (``decision_ms``, ``mask_ms``) and
the scenario's ``digest`` (which files before schema 1 lack); any other field present
on one side only is a difference. Prints the counts and the first differences; exits 1
when any record differs or is missing on one side.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

TIMINGS = {"decision_ms", "mask_ms"}
IGNORED = TIMINGS | {"digest"}  # fields not compared


def records(path: Path, policies: set[str] | None) -> dict[tuple, dict]:
    data = json.loads(path.read_text())
    rows = data["records"] if isinstance(data, dict) else data
    return {
        (r["policy"], r["split"], r["source"], r["seed"]): {k: v for k, v in r.items() if k not in IGNORED}
        for r in rows
        if policies is None or r["policy"] in policies
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--policies", nargs="+")
    args = parser.parse_args()
    wanted = set(args.policies) if args.policies else None
    before, after = records(args.before, wanted), records(args.after, wanted)
    missing = sorted(set(before) ^ set(after))
    differ = [key for key in sorted(set(before) & set(after)) if before[key] != after[key]]
    by_policy: dict[str, list[int]] = {}
    for key in set(before) & set(after):
        by_policy.setdefault(key[0], [0, 0])
        by_policy[key[0]][0] += before[key] == after[key]
        by_policy[key[0]][1] += 1
    for policy, (same, total) in sorted(by_policy.items()):
        print(f"{policy}: {same} of {total} records identical (timings and digests aside)")
    for key in missing[:5]:
        print("only on one side:", key)
    for key in differ[:5]:
        fields = sorted(k for k in before[key].keys() | after[key].keys() if before[key].get(k) != after[key].get(k))
        print("differs:", key, {f: (before[key].get(f), after[key].get(f)) for f in fields})
    return 1 if missing or differ else 0


if __name__ == "__main__":
    sys.exit(main())
