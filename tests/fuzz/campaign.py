"""A longer fuzz campaign than the test suite runs: counts of what happens to mutated files, by outcome.

Run from the repository root::

    PYTHONPATH=. python tests/fuzz/campaign.py --examples 2000
    PYTHONPATH=. python tests/fuzz/campaign.py --timings

It draws mutated scenario files, plan files and (scenario, plan) pairs for
``fetchcarry validate`` with the strategies of :mod:`mutations` (derandomized: the
same files every run) and prints, for each, how many ended in each outcome. A crash
is any exception other than the documented one (or an exit status other than 0, 1, 2,
or a traceback on stderr); the campaign lists the first few of them.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
from collections import Counter
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent))

from mutations import file_bytes, mutated, to_json_text, write_mutated
from test_fuzz_inputs import PLAN_FILE, SCENARIO, VALID_PLAN, VALID_SCENARIO

from expert.plans import Plan, PlanFormatError
from expert.validate import validate_plan
from fetchcarry_env.scenario import Scenario, ScenarioError
from training.cli import main


def _kind(message: str) -> str:
    """The category of a violation message: its rule, or the kind of format problem."""
    head = message.split(":")[0]
    if head.startswith(("rule ", "structure")):
        return head
    for words in ("not a text file", "not a UTF-8", "nested too deeply", "not valid JSON", "unknown key", "bytes"):
        if words in message:
            return f"format ({words})"
    return "format (wrong or missing value)"


def campaign(examples: int, workdir: Path) -> dict[str, Counter]:
    counts: dict[str, Counter] = {"scenario": Counter(), "plan": Counter(), "validate": Counter()}
    crashes: list[str] = []
    config = settings(
        max_examples=examples,
        derandomize=True,
        database=None,
        deadline=None,
        suppress_health_check=list(HealthCheck),
    )

    @config
    @given(data=st.data())
    def scenarios(data):
        path = write_mutated(data, workdir / "s.json", VALID_SCENARIO)
        try:
            Scenario.load(path)
            counts["scenario"]["accepted"] += 1
        except ScenarioError as error:
            counts["scenario"][f"ScenarioError: {_kind(error.violations[0])}"] += 1
        except Exception as error:
            counts["scenario"]["CRASH"] += 1
            crashes.append(f"scenario: {type(error).__name__}: {str(error)[:200]}")

    @config
    @given(data=st.data())
    def plans(data):
        path = write_mutated(data, workdir / "p.json", VALID_PLAN)
        try:
            violations = validate_plan(SCENARIO, Plan.load(path))
            counts["plan"]["read, valid" if not violations else f"read, invalid: {_kind(violations[0])}"] += 1
        except PlanFormatError:
            counts["plan"]["PlanFormatError"] += 1
        except Exception as error:
            counts["plan"]["CRASH"] += 1
            crashes.append(f"plan: {type(error).__name__}: {str(error)[:200]}")

    @config
    @given(data=st.data(), which=st.sampled_from(["scenario", "plan", "both"]))
    def cli(data, which):
        scenario_text, plan_text = to_json_text(VALID_SCENARIO), to_json_text(VALID_PLAN)
        if which != "plan":
            scenario_text = to_json_text(data.draw(mutated(VALID_SCENARIO)))
        if which != "scenario":
            plan_text = to_json_text(data.draw(mutated(VALID_PLAN)))
        (workdir / "cs.json").write_bytes(data.draw(file_bytes(scenario_text)))
        (workdir / "cp.json").write_bytes(data.draw(file_bytes(plan_text)))
        err = io.StringIO()
        try:
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
                status = main(["validate", str(workdir / "cs.json"), str(workdir / "cp.json")])
        except SystemExit as exit_:
            status = exit_.code
        except Exception as error:
            status = f"CRASH ({type(error).__name__})"
            crashes.append(f"validate: {type(error).__name__}: {str(error)[:200]}")
        if "Traceback" in err.getvalue():
            status = f"{status} with a traceback"
        counts["validate"][f"exit {status}"] += 1

    scenarios()
    plans()
    cli()
    counts["crashes"] = Counter(crashes[:10])
    return counts


def timings() -> None:
    """Seconds to load the largest scenarios and to validate long plans on 1,024 obstacles (printed)."""
    import json
    import time
    from dataclasses import replace

    from test_fuzz_inputs import HAND, scenario_with_obstacles

    with tempfile.TemporaryDirectory() as folder:
        huge = copy_of_example(obstacles=300_000)
        path = Path(folder) / "huge.json"
        path.write_text(json.dumps(huge, indent=1))
        started = time.perf_counter()
        with contextlib.suppress(ScenarioError):
            Scenario.load(path)
        print(f"refuse 300,000 obstacles ({path.stat().st_size / 1e6:.0f} MB): {time.perf_counter() - started:.2f} s")
    started = time.perf_counter()
    scenario = Scenario.from_dict(scenario_with_obstacles(1024))
    print(f"load and check 1,024 obstacles: {time.perf_counter() - started:.3f} s")
    for label, far in (("back and forth", (4.0, 0.5)), ("diagonal across the posts", (59.0, 59.0))):
        near = (4.0, 0.0) if far == (4.0, 0.5) else (9.0, 9.0)
        moves = [replace(HAND.phases[1], base=base) for _ in range(1000) for base in (near, far)]
        plan = replace(HAND, phases=(HAND.phases[0], *moves, *HAND.phases[1:]))
        started = time.perf_counter()
        found = validate_plan(scenario, plan)
        print(
            f"validate {len(plan.phases):,} phases ({label}), 1,024 obstacles: {time.perf_counter() - started:.2f} s, "
            f"{len(found):,} violations"
        )


def copy_of_example(obstacles: int) -> dict:
    """The example scenario with ``obstacles`` copies of its box (for the refusal by count)."""
    import copy

    document = copy.deepcopy(VALID_SCENARIO)
    document["obstacles"] = [{"id": f"box_{i}", "min": [2.8, 2.9], "max": [3.2, 3.3]} for i in range(obstacles)]
    return document


def main_(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--examples", type=int, default=1000, help="files drawn for each of the three targets")
    parser.add_argument("--timings", action="store_true", help="print load and validation times instead")
    args = parser.parse_args(argv)
    if args.timings:
        timings()
        return 0
    with tempfile.TemporaryDirectory() as folder:
        counts = campaign(args.examples, Path(folder))
    for target, counter in counts.items():
        print(f"{target} ({sum(counter.values())})")
        for outcome, count in counter.most_common():
            print(f"  {count:6d}  {outcome}")
    print(f"starting points: {PLAN_FILE.name} and examples/push_basic.json")
    return 1 if counts["crashes"] else 0


if __name__ == "__main__":
    sys.exit(main_())
